#!/bin/sh
# Issue 62, item 2: stage 2 warm-started at pretrained:brownian (keyin_plus, argmax-offset F1 0.872 on 300
# val clips) and trained on the paper's loss alone (teacher weight 0), lr 1e-3, batch 30, a fresh Adam,
# seeds 0-2; validation (300 val clips: argmax F1, each loss term, δ's entropy, keyframes per clip,
# distinct patterns) every 100 steps. Resumable: run it again and each seed continues from its last.ckpt
# (a finished seed is skipped).
#   sh docs/results/warm_start_brownian/scripts/run.sh <jobs dir> <data dir> [seeds...]
set -eu
jobs=$1; data=$2; shift 2
seeds=${*:-0 1 2}
for seed in $seeds; do
  OMP_NUM_THREADS=1 keyin-train model=keyin_plus stage=keyframes init_ckpt=pretrained:brownian \
    model.keyframes.teacher_weight=0 model.keyframes.discovery=offsets \
    scale.stage2_steps=1000 scale.val_every=100 scale.val_clips=300 scale.checkpoint_every=250 \
    seed="$seed" data_dir="$data" evaluate=false hydra.run.dir="$jobs/warm_brownian_seed$seed"
done
