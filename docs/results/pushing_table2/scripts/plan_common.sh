# sourced: the frozen checkout, one thread per process, the table's checkpoint pattern
cd /work/run-tree10
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl
PY=/work/main/.venv/bin/python
T1=runs/multirun/pushing_table1
MODELS=models/pushing_table2
CKPT='planner.checkpoint=models/pushing_table2/${planner.model}_seed${planner.model_seed}.ckpt'
wait_for() { while [ ! -f "$1" ]; do sleep 30; done; }
export_job() {  # export_job <job>: slim its stage 2 into $MODELS unless there already
  [ -f $MODELS/$1.ckpt ] || $PY -m keyin.pretrained export $T1/$1/checkpoints/keyframes/last.ckpt --folder $MODELS
}
plan() {  # plan <seed> <overrides...>
  seed=$1; shift
  date; $PY -m keyin.cli.plan -m experiment=pushing_table2 "$@" seed=$seed workers=1 "$CKPT" progress=false
}
