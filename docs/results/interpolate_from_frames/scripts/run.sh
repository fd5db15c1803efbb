#!/bin/sh
# Issue 62, item 3: the paper's stage 2 from scratch with the one reading that held the truth in the warm start
# (the interpolator reads the embeddings of the frames δ selects, model.keyframes.interpolate_from=frames), beside
# the grid's baseline row (docs/results/paper_stage2_grid: the same stage 1, seed, budget and everything else).
#   sh docs/results/interpolate_from_frames/scripts/run.sh <jobs dir> <data dir> [seed]
set -eu
jobs=$1; data=$2; seed=${3:-1}
OMP_NUM_THREADS=1 keyin-train model=keyin_paper model.name=keyin_paper_frames model.keyframes.interpolate_from=frames \
  backbone=ours stage=keyframes interpolator_ckpt=pretrained:brownian seed="$seed" data_dir="$data" \
  hydra.run.dir="$jobs/interpolate_from_frames_seed$seed"
