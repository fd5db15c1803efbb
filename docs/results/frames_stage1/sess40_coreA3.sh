#!/bin/sh
# Issue 25, stop 40: stage 2 on the frozen-autoencoder stage 1 of pushing_irregular (seed 0): the paper's KEYIN,
# Jumpy, Static, then keyin_plus, each scored on the 1000 test clips. Frozen checkout /work/run-tree17; resumable.
cd /work/run-tree17
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree17
PY=/work/main/.venv/bin/python
AE=/work/run-tree15/runs/frames/pushing_w8_s6000/checkpoints/frames/last.ckpt
for m in keyin jumpy static keyin_plus; do
  /usr/bin/time -f "$m irregular frames %e s" $PY -m keyin.cli.train -m experiment=pushing_irregular_table1 backbone=frames \
    backbone.frames_ckpt=$AE name=pushing_irregular_frames stage1_dir=runs/frames_stage1/pushing_irregular model=$m seed=0
done
