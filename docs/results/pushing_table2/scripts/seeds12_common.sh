# sourced: the frozen checkout /work/run-tree11, one thread per process, the table's checkpoint pattern
cd /work/run-tree11
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl
PY=/work/main/.venv/bin/python
T1=runs/multirun/pushing_table1
MODELS=models/pushing_table2
CKPT='planner.checkpoint=models/pushing_table2/${planner.model}_seed${planner.model_seed}.ckpt'
wait_for() { while [ ! -f "$1" ]; do sleep 30; done; }
train() {  # train <model> <seed>: pushing Table 1's job, then slim its stage 2 into $MODELS
  date; [ -f $T1/$1_seed$2/metrics.json ] || $PY -m keyin.cli.train -m experiment=pushing_table1 model=$1 seed=$2 trainer.enable_progress_bar=false
  [ -f $MODELS/$1_seed$2.ckpt ] || $PY -m keyin.pretrained export $T1/$1_seed$2/checkpoints/keyframes/last.ckpt --folder $MODELS
}
plan() {  # plan <seed> <overrides...>
  seed=$1; shift
  date; $PY -m keyin.cli.plan -m experiment=pushing_table2 "$@" seed=$seed workers=1 "$CKPT" progress=false
}
