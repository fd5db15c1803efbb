#!/bin/sh
# Issue 45 item 1: TAP before (e87095b, /work/run-tree) and after the minimum-over-time fix (/work/run-tree4),
# seed 0 each, then seeds 1-2 after; where their predictions land on the 1000 test clips, one rule (today's).
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl
PY=/work/main/.venv/bin/python



for s in 0 1 2; do
  cd /work/run-tree4 && PYTHONPATH=/work/run-tree4 /usr/bin/time -f "tap after seed$s %e s" $PY -m keyin.cli.train experiment=pushing_table1 model=tap \
    seed=$s logger=csv hydra.run.dir=runs/tap/after_seed$s skip_finished=true
done
cd /work/main
for run in /work/run-tree/runs/tap/before_seed0 /work/run-tree4/runs/tap/after_seed0 /work/run-tree4/runs/tap/after_seed1 /work/run-tree4/runs/tap/after_seed2; do
  name=$(basename $(dirname $(dirname $run)))_$(basename $run)
  $PY studies/tap_landing.py $run/checkpoints/tap/last.ckpt --split test --clips 1000 --data-dir /work/run-tree/data \
    --out studies/results/tap_landing_$(basename $run).md
done
