#!/bin/sh
# Issue 24: pushing Surprise seed 1 (its own model, no stage 1), the last missing pushing Table 1 job.
# Resumable: rerun; a finished job is skipped. Frozen checkout /work/run-tree7 (runs/, data/ link to /work/main's).
cd /work/run-tree7
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl
exec /work/main/.venv/bin/python -m keyin.cli.train -m experiment=pushing_table1 model=surprise seed=1
