#!/bin/sh
# Issue 43: the grid's two rows not run yet (unnormalised K̃, unscaled attention), then issue 45's servo-horizon
# check of No subgoals (l = 16, 32 on tasks 0-39); frozen checkout /work/run-tree5, one process, resumable.
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree5
cd /work/run-tree5
PY=/work/main/.venv/bin/python
$PY -m keyin.cli.reproduce table=paper_stage2_grid 'steps=[jobs]' dry_run=true 2>/dev/null | grep '^+ ' | sed 's/^+ python //' |
while read -r cmd; do
  arm=$(echo "$cmd" | sed 's/.*hydra.sweep.subdir=\([^ ]*\).*/\1/')
  case "$arm" in unnormalised|attn_unscaled) ;; *) continue ;; esac
  echo "$(date +%T) $arm start"
  eval /usr/bin/time -f "'$arm %e s'" $PY $cmd logger=csv < /dev/null > runs/round4_$arm.log 2>&1
  echo "$(date +%T) $arm done: $(tail -1 runs/round4_$arm.log)"
done
$PY -m keyin.cli.plan -m experiment=pushing_table2 planner=no_subgoals seed=0 workers=1 tasks=40 'planner.servo_horizon=16,32' 'hydra.sweep.subdir=${planner.name}_horizon${planner.servo_horizon}_seed${seed}'
