#!/bin/sh
# Issue 28: Table 2 rows that need no training on this machine, 240 fixed tasks, workers=2, both cores
# free: KEYIN with model seed 0 (the shipped pretrained:pushing, pushing Table 1's keyin_plus_seed0),
# then initial, random and demo_subgoals. Resumable: rerun; finished tasks are skipped (tasks.jsonl).
# Frozen checkout /work/run-tree8 (its runs/ and data/ link to /work/main's).
cd /work/run-tree8
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl
PY=/work/main/.venv/bin/python
$PY -m keyin.cli.generate dataset=pushing 'splits={planning: 240}' progress=false &&
$PY -m keyin.cli.plan -m experiment=pushing_table2 planner=keyin seed=0 workers=2 planner.checkpoint=pretrained:pushing progress=false &&
exec $PY -m keyin.cli.plan -m experiment=pushing_table2 planner=initial,random,demo_subgoals seed=0 workers=2 progress=false
