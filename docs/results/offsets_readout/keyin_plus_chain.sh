#!/bin/sh
# Issue 26 item 2: keyin_plus with the teacher read along its own path (teacher_chain=true), stage 2 only,
# on the Brownian Table 1 sweep's stage 1 of seed 0 (the same one keyin_plus_seed0 trains on). Frozen checkout run-tree2.
cd /work/run-tree2
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
RUN=runs/long/keyin_plus_chain_seed0
if [ -d $RUN/checkpoints ]; then R="resume=$RUN"; else R=""; fi
exec /work/main/.venv/bin/python -m keyin.cli.train experiment=brownian_keyin model=keyin_plus seed=0 stage=keyframes \
  interpolator_ckpt=runs/multirun/brownian_table1/stage1_ours_seed0/checkpoints/interpolator/last.ckpt \
  model.keyframes.teacher_chain=true model.keyframes.discovery=offsets hydra.run.dir=$RUN $R
