#!/bin/sh
# Issue 43: the grid's small files, report, validation curves and table into docs/results/paper_stage2_grid
export OMP_NUM_THREADS=1
G=/work/run-tree3/runs/multirun/paper_stage2_grid
OUT=/work/main/docs/results/paper_stage2_grid
cd /work/run-tree3 && PYTHONPATH=/work/run-tree3 /work/main/.venv/bin/python -m keyin.cli.reproduce table=paper_stage2_grid 'steps=[collect,report]' out=$OUT > /tmp/collect.log 2>&1 || tail -5 /tmp/collect.log
cd /work/main
ARGS=""
for d in $G/*/; do a=$(basename $d); [ -f $d/metrics.json ] && ARGS="$ARGS $a=$d"; done
.venv/bin/python studies/training_curves.py $ARGS --out $OUT/curves.png --table $OUT/validation.csv > /dev/null
.venv/bin/python studies/stage2_grid.py $OUT --out $OUT/grid.md
