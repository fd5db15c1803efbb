#!/bin/sh
set -eu
jobs=$1; data=$2; seed=${3:-1}
OMP_NUM_THREADS=1 keyin-train model=keyin_paper model.name=keyin_paper_frames_entropy model.keyframes.interpolate_from=frames \
  model.keyframes.entropy_bonus=50 model.keyframes.entropy_bonus_steps=1000 \
  backbone=ours stage=keyframes interpolator_ckpt=pretrained:brownian seed="$seed" data_dir="$data" \
  hydra.run.dir="$jobs/interpolate_from_frames_entropy_seed$seed"
