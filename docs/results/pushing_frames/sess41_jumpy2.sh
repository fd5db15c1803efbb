#!/bin/sh
# Stop 41 (issue 25): jumpy, seed 2, on the frozen-autoencoder stage 1 of pushing_irregular (stage1_frames_seed2). Frozen checkout /work/run-tree17.
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree17
PY=/work/main/.venv/bin/python
AE=/work/run-tree15/runs/frames/pushing_w8_s6000/checkpoints/frames/last.ckpt
cd /work/run-tree17
/usr/bin/time -f "jumpy irregular frames seed2 %e s" $PY -m keyin.cli.train -m experiment=pushing_irregular_table1 \
  backbone=frames backbone.frames_ckpt=$AE name=pushing_irregular_frames model=jumpy seed=2 skip_finished=true
