#!/bin/sh
# Issue 24: second core. Brownian keyin_evidence seed 0 (retrains that seed's stage 1: the machine was
# replaced), pushing seed 2's untrained rows and Surprise seed 2 (no stage 1), then, once keyin_plus seed 2
# is scored, Static seed 2 on its stage 1 and map at alpha = 0 on keyin_plus seed 2; then Surprise seed 0.
cd /work/run-tree7
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl
PY=/work/main/.venv/bin/python
$PY -m keyin.cli.train -m experiment=brownian_table1 model=keyin_evidence seed=0
while pgrep -f "keyin-generate dataset=pushing" > /dev/null; do sleep 20; done
$PY -m keyin.cli.train -m experiment=pushing_table1 model=constant,random,changepoint,changepoint_frames,surprise seed=2
while [ ! -f runs/multirun/pushing_table1/keyin_plus_seed2/metrics.json ]; do sleep 30; done
$PY -m keyin.cli.train -m experiment=pushing_table1 model=static seed=2
$PY -m keyin.cli.eval -m seed=2 "ckpt=runs/multirun/pushing_table1/keyin_plus_seed\${seed}/checkpoints/keyframes/last.ckpt" "discovery=[segmentation]" skip_finished=true progress=false hydra.sweep.dir=runs/multirun/pushing_table1 "hydra.sweep.subdir=keyin_plus_segmentation_seed\${seed}"
exec $PY -m keyin.cli.train -m experiment=pushing_table1 model=surprise seed=0
