#!/bin/sh
# Issue 25, 2026-12-04 (stop 39), after frames_pushing.sh: do more steps pay? The same frame autoencoders for
# 6000 steps, width $1 (run once per core: `sh frames_pushing_6000.sh 8 & sh frames_pushing_6000.sh 16`).
cd ${TREE:-/work/main}
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=$PWD  # this tree's keyin, not the editable install's
PY=${PY:-/work/main/.venv/bin/python}
date; $PY -m keyin.cli.train model=frame_autoencoder dataset=pushing backbone=ours seed=0 scale.conv_width=$1 \
  scale.frames_steps=6000 trainer.enable_progress_bar=false hydra.run.dir=runs/frames/pushing_w$1_s6000
$PY studies/stage1_objects.py runs/frames/pushing_w$1_s6000/checkpoints/frames/last.ckpt --split val --clips 200 \
  > studies/results/stage1_objects_frames_w$1_s6000.md
date
