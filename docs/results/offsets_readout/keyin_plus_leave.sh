#!/bin/sh
# (The row "price 25 nats, interior only" ran this script from /work/run-tree2, main at d84b8f5, before the leaving teacher existed.)
# Issue 26 item 2: keyin_plus whose teacher also teaches the keyframe after the last interior one to
# leave the clip (keyin 0.2, run-tree3 = main at the commit of that change); stage 2 only on the Brownian
# Table 1 sweep's stage 1 of seed 0; $1 = extra overrides' label, rest = overrides. No test scoring
# (measured on validation clips by studies/readout_chain.py).
cd /work/run-tree3
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
NAME=$1; shift
RUN=runs/long/$NAME
if [ -d $RUN/checkpoints ]; then R="resume=$RUN"; else R=""; fi
exec /work/main/.venv/bin/python -m keyin.cli.train experiment=brownian_keyin model=keyin_plus seed=0 stage=keyframes \
  interpolator_ckpt=runs/multirun/brownian_table1/stage1_ours_seed0/checkpoints/interpolator/last.ckpt \
  model.keyframes.discovery=offsets evaluate=false hydra.run.dir=$RUN $R "$@"
