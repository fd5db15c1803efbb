#!/bin/sh
# Issue 26 item 1: the paper's KEYIN (model=keyin backbone=paper) at CPU sizes, stage 2 for 20k steps (resumable: rerun).
# It ran before backbone=paper carried the paper's stage-2 freezing and δ̂ (2026-12-06): the pins below keep what it
# ran, all of stage 1 frozen and soft δ. Started from /work/main; resumed in the frozen checkout /work/run-tree2 (its runs/ links to /work/main/runs).
cd /work/run-tree2
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
RUN=runs/long/brownian_keyin_paper_20k
if [ -d $RUN/checkpoints ]; then R="resume=$RUN"; else R=""; fi
exec /work/main/.venv/bin/python -m keyin.cli.train experiment=brownian_keyin model=keyin backbone=paper seed=0 \
  scale.stage2_steps=20000 scale.val_every=500 \
  model.keyframes.frozen=stage1 model.keyframes.delta_input=soft hydra.run.dir=$RUN $R
