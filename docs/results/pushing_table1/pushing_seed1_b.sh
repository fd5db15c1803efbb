#!/bin/sh
# Issue 24: pushing Table 1 seed 1 on the second core once the Brownian jobs are done: Static and the
# untrained rows (the seed's stage 1 exists, so no race), then map at alpha = 0 on keyin_plus seed 1.
cd /work/run-tree6
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
while pgrep -f brownian_static_jumpy.sh > /dev/null; do sleep 15; done
/work/main/.venv/bin/python -m keyin.cli.train -m experiment=pushing_table1 model=static,constant,random,changepoint,changepoint_frames seed=1
exec /work/main/.venv/bin/python -m keyin.cli.eval -m seed=1 "ckpt=runs/multirun/pushing_table1/keyin_plus_seed\${seed}/checkpoints/keyframes/last.ckpt" "discovery=[segmentation]" skip_finished=true progress=false hydra.sweep.dir=runs/multirun/pushing_table1 "hydra.sweep.subdir=keyin_plus_segmentation_seed\${seed}"
