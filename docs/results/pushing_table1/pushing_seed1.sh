#!/bin/sh
# Issue 24/28: pushing Table 1, seed 1 over the trained and untrained rows (resumable: rerun; finished jobs are skipped),
# then the table's segmentation eval (map at alpha = 0) on keyin_plus seed 1.
# Frozen checkout /work/run-tree6 (its runs/ and data/ link to /work/main's). Waits for the pushing data.
cd /work/run-tree6
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
while pgrep -f "keyin-generate dataset=pushing" > /dev/null; do sleep 20; done
/work/main/.venv/bin/python -m keyin.cli.train -m experiment=pushing_table1 model=keyin_plus,keyin,jumpy,static,random,constant,changepoint,changepoint_frames seed=1
exec /work/main/.venv/bin/python -m keyin.cli.eval -m seed=1 "ckpt=runs/multirun/pushing_table1/keyin_plus_seed\${seed}/checkpoints/keyframes/last.ckpt" "discovery=[segmentation]" skip_finished=true progress=false hydra.sweep.dir=runs/multirun/pushing_table1 "hydra.sweep.subdir=keyin_plus_segmentation_seed\${seed}"
