#!/bin/sh
# Issue 45: Surprise (SVG's skips) trained and planned with seeds 1-2, beside TAP seed 2 (split from
# issue45_seeds.sh so both run on the two cores). Frozen checkout /work/run-tree5; resumable.
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree5
cd /work/run-tree5
PY=/work/main/.venv/bin/python
$PY -m keyin.cli.train -m experiment=pushing_table1 model=surprise seed=1,2 model.module.skips=true 'hydra.sweep.subdir=surprise_skips_seed${seed}' logger=csv skip_finished=true
$PY -m keyin.cli.plan -m experiment=pushing_table2 planner=surprise seed=1,2 workers=1 'planner.checkpoint=runs/multirun/pushing_table1/surprise_skips_seed${seed}/checkpoints/surprise/last.ckpt'
