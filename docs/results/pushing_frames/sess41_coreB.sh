#!/bin/sh
# Stop 41, core B (issue 25): pushing_irregular seed 1 on the frozen autoencoder: its own stage 1 (trained by the first
# job), then the paper's KEYIN, Jumpy and Static. Frozen checkout /work/run-tree17; resumable.
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree17
PY=/work/main/.venv/bin/python
AE=/work/run-tree15/runs/frames/pushing_w8_s6000/checkpoints/frames/last.ckpt
cd /work/run-tree17
for m in keyin_paper jumpy static; do
  /usr/bin/time -f "$m irregular frames seed1 %e s" $PY -m keyin.cli.train -m experiment=pushing_irregular_table1 \
    backbone=frames backbone.frames_ckpt=$AE name=pushing_irregular_frames model=$m seed=1 skip_finished=true
done
