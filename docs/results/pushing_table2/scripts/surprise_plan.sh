#!/bin/sh
# Issue 45: plan Surprise seed $2 once process $1 (the job ahead of it on this core) has exited. Frozen
# checkout /work/run-tree5; resumable (finished tasks are skipped).
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree5
cd /work/run-tree5
while kill -0 $1 2>/dev/null; do sleep 20; done
/work/main/.venv/bin/python -m keyin.cli.plan -m experiment=pushing_table2 planner=surprise seed=$2 workers=1 'planner.checkpoint=runs/multirun/pushing_table1/surprise_skips_seed${seed}/checkpoints/surprise/last.ckpt'
