#!/bin/sh
# Issue 25, 2026-12-04 (stop 39): the frame autoencoder on the pushing demos at scale=cpu (backbone=ours:
# GroupNorm, coordinate planes, changed pixels x20), conv_width 8 (the joint stage 1's) and 16, one torch
# thread each; then where each draws the objects on 200 validation clips, and the committed keyin_plus seed 1's
# stage 1 (trained jointly with its interpolator, 2000 steps) for comparison; the time to cache the
# 1000 validation clips' embeddings.
cd ${TREE:-/work/main}
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=$PWD  # this tree's keyin, not the editable install's
PY=${PY:-/work/main/.venv/bin/python}
for width in 8 16; do
  date; $PY -m keyin.cli.train model=frame_autoencoder dataset=pushing backbone=ours seed=0 scale.conv_width=$width \
    scale.frames_steps=2000 trainer.enable_progress_bar=false hydra.run.dir=runs/frames/pushing_w$width
  $PY studies/stage1_objects.py runs/frames/pushing_w$width/checkpoints/frames/last.ckpt --split val --clips 200 \
    > studies/results/stage1_objects_frames_w$width.md
  $PY benchmarks/encode_split.py runs/frames/pushing_w$width/checkpoints/frames/last.ckpt --split val \
    > benchmarks/results/encode_split_frames_w$width.md
done
$PY studies/stage1_objects.py models/pushing_table2/keyin_plus_seed1.ckpt --split val --clips 200 \
  > studies/results/stage1_objects_keyin_plus_seed1.md
date
