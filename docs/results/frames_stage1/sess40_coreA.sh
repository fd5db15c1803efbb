#!/bin/sh
# Issue 25, stop 40: stage 1 on the frozen width-8 frame autoencoder (backbone=frames) on dataset=pushing,
# then its gates on the first 200 validation clips: the exact segmentation's keyframes (keyin-eval of the
# stage-1 checkpoint) and where it draws the puck and pusher (studies/stage1_objects.py); the joint
# stage 1 of the committed keyin_plus seed 1 scored alike. Frozen checkout /work/run-tree17; resumable.
cd /work/run-tree17
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree17
PY=/work/main/.venv/bin/python
AE=/work/run-tree15/runs/frames/pushing_w8_s6000/checkpoints/frames/last.ckpt
RUN=runs/frames_stage1/pushing
while pgrep -f "dataset=pushing_irregular workers=1" >/dev/null; do sleep 10; done
/usr/bin/time -f "stage1 %e s" $PY -m keyin.cli.train model=keyin_plus dataset=pushing backbone=frames backbone.frames_ckpt=$AE \
  stage=interpolator hydra.run.dir=$RUN
/usr/bin/time -f "gate %e s" $PY -m keyin.cli.eval ckpt=$RUN/checkpoints/interpolator/last.ckpt dataset=pushing split=val clips=200 \
  progress=false hydra.run.dir=runs/frames_stage1/gate_pushing
$PY studies/stage1_objects.py $RUN/checkpoints/interpolator/last.ckpt --split val --clips 200 > runs/frames_stage1/objects_pushing.md
/usr/bin/time -f "gate joint %e s" $PY -m keyin.cli.eval ckpt=/work/main/models/pushing_table2/keyin_plus_seed1.ckpt \
  dataset=pushing split=val clips=200 'discovery=[segmentation]' progress=false hydra.run.dir=runs/frames_stage1/gate_joint_pushing
