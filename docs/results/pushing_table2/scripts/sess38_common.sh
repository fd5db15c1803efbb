# sourced: the frozen checkout /work/run-tree12, one thread per process, the table's checkpoint pattern
cd /work/run-tree12
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl
PY=/work/main/.venv/bin/python
T1=runs/multirun/pushing_table1
CKPT='planner.checkpoint=models/pushing_table2/${planner.model}_seed${planner.model_seed}.ckpt'
SUBDIR='hydra.sweep.subdir=${planner.name}_${planner.servo_observe}_repeat${planner.servo_action_repeat}_seed${seed}'
plan() {  # plan <overrides...>: one process, seed 0 unless overridden
  date; $PY -m keyin.cli.plan -m experiment=pushing_table2 seed=0 workers=1 progress=false "$@"
}
sensitivity() {  # sensitivity <planner overrides...>: the first 80 tasks in the three other servo settings
  plan "$@" tasks=80 'planner.servo_observe=state,pixels' planner/low_level@planner=servo_env_steps "$SUBDIR"
  plan "$@" tasks=80 planner.servo_observe=pixels "$SUBDIR"
}
