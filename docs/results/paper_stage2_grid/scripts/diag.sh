#!/bin/sh
# diagnostics (200 val clips) of every finished grid arm not yet diagnosed
export OMP_NUM_THREADS=1
G=/work/run-tree3/runs/multirun/paper_stage2_grid
D=/work/main/docs/results/paper_stage2_grid/diagnostics
mkdir -p $D
for m in $G/*/metrics.json; do
  arm=$(basename $(dirname $m))
  [ -f $D/$arm.md ] && continue
  cd /work/main && .venv/bin/python studies/stage2_diagnostics.py $G/$arm/checkpoints/keyframes/last.ckpt --clips 200 --data-dir /work/run-tree/data --out $D/$arm.md > /dev/null 2>&1 && echo "$arm diagnosed"
done
