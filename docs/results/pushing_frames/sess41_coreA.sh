#!/bin/sh
# Stop 41, core A (issue 25): the paper's KEYIN (stage 2) on the frozen-autoencoder stage 1 of pushing, scored on the
# 1000 test clips; then Table 2's KEYIN row re-planned with it (240 tasks, one process); then pushing_irregular seed 2
# of the paper's KEYIN (its own stage 1 first). Frozen checkout /work/run-tree17; resumable.
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree17
PY=/work/main/.venv/bin/python
AE=/work/run-tree15/runs/frames/pushing_w8_s6000/checkpoints/frames/last.ckpt
cd /work/run-tree17
/usr/bin/time -f "keyin_paper pushing frames train %e s" $PY -m keyin.cli.train -m experiment=pushing_table1 backbone=frames \
  backbone.frames_ckpt=$AE name=pushing_frames stage1_dir=runs/frames_stage1/pushing model=keyin_paper seed=0 skip_finished=true
RUN=runs/table2_frames/keyin_paper_seed0
if [ -d $RUN ]; then R="resume=$RUN"; else R=""; fi
/usr/bin/time -f "keyin_paper frames plan %e s" $PY -m keyin.cli.plan planner=keyin planner.model=keyin_paper \
  planner.checkpoint=runs/multirun/pushing_frames/keyin_paper_seed0/checkpoints/keyframes/last.ckpt seed=0 workers=1 \
  progress=false hydra.run.dir=$RUN $R
/usr/bin/time -f "keyin_paper irregular frames seed2 %e s" $PY -m keyin.cli.train -m experiment=pushing_irregular_table1 \
  backbone=frames backbone.frames_ckpt=$AE name=pushing_irregular_frames model=keyin_paper seed=2 skip_finished=true
