#!/bin/sh
# Issue 45: the fixed TAP (models/tap_fixed) planned with seeds 0-2, then Surprise (SVG's skips)
# trained and planned with seeds 1-2, as conf/table/pushing_table2.yaml's rows run them but one process at a
# time (workers=1: the planning seeds are per task, the worker count changes only the wall time). Frozen
# checkout /work/run-tree5 (its keyin/conf a link to its conf/); resumable (finished tasks are skipped).
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree5
cd /work/run-tree5
PY=/work/main/.venv/bin/python
$PY -m keyin.cli.plan -m experiment=pushing_table2 planner=tap seed=0,1,2 workers=1 'planner.checkpoint=models/tap_fixed/after_seed${seed}.ckpt'
$PY -m keyin.cli.train -m experiment=pushing_table1 model=surprise seed=1,2 model.module.skips=true 'hydra.sweep.subdir=surprise_skips_seed${seed}' logger=csv skip_finished=true
$PY -m keyin.cli.plan -m experiment=pushing_table2 planner=surprise seed=1,2 workers=1 'planner.checkpoint=runs/multirun/pushing_table1/surprise_skips_seed${seed}/checkpoints/surprise/last.ckpt'
