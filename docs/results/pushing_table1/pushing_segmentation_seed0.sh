#!/bin/sh
# pushing Table 1: map with alpha = 0 (stage 1's segmentation at keyin_plus's price) on keyin_plus seed 0 (the table config's eval sweep, seed 0).
cd /work/run-tree5
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
while pgrep -f after_pushing_keyin_plus.sh > /dev/null; do sleep 20; done
exec /work/main/.venv/bin/python -m keyin.cli.eval -m seed=0 "ckpt=runs/multirun/pushing_table1/keyin_plus_seed\${seed}/checkpoints/keyframes/last.ckpt" "discovery=[segmentation]" skip_finished=true progress=false hydra.sweep.dir=runs/multirun/pushing_table1 "hydra.sweep.subdir=keyin_plus_segmentation_seed\${seed}"
