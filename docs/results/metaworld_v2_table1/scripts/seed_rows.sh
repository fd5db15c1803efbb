#!/bin/sh
# Issue 46: one seed's learned rows of the Meta-World v2 Table 1, on one core, the rows the target names first:
# keyin_plus (it trains the seed's stage 1), keyin_paper, stage 1's exact segmentation of the test clips, then
# Jumpy and Static on the same stage 1. The machine was replaced on 2026-12-06 with seeds 1-2 half-trained
# (runs/ and data/ lost; seed 0 and the untrained rows were committed, core_a.sh and core_b.sh); seeds 1 and 2
# run from here, one per core, after `keyin-generate dataset=metaworld_v2` in the same frozen checkout:
#   cd /work/run-tree9 && setsid nohup sh /work/main/docs/results/metaworld_v2_table1/scripts/seed_rows.sh 1 > seed1.log 2>&1 &
# Resumable: skip_finished, last.ckpt; a row already committed under docs/results/metaworld_v2_table1/jobs is
# not run again (on a fresh machine Jumpy then trains the seed's stage 1 first, into the same shared folder).
SEED=$1
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree9
cd /work/run-tree9
PY=${PY:-/work/main/.venv/bin/python}
SWEEP=runs/multirun/metaworld_v2_table1
COMMITTED=/work/main/docs/results/metaworld_v2_table1/jobs
todo() { [ ! -f $COMMITTED/$1_seed$SEED/metrics.json ]; }
for model in keyin_plus keyin_paper; do
  todo $model && $PY -m keyin.cli.train -m experiment=metaworld_v2_table1 model=$model seed=$SEED logger=csv skip_finished=true
done
KEYFRAMES=$SWEEP/keyin_plus_seed$SEED/checkpoints/keyframes/last.ckpt
if todo keyin_plus_segmentation && [ -f $KEYFRAMES ]; then  # stage 1's exact segmentation (the table's eval sweep)
  $PY -m keyin.cli.eval -m seed=$SEED ckpt=$KEYFRAMES "discovery=[segmentation]" skip_finished=true progress=false hydra.sweep.dir=$SWEEP hydra.sweep.subdir=keyin_plus_segmentation_seed$SEED
elif todo keyin_plus_segmentation; then
  echo "keyin_plus_segmentation seed $SEED skipped: no $KEYFRAMES (its keyin_plus was trained on another machine; train it again to run this row)"
fi
for model in jumpy static; do
  todo $model && $PY -m keyin.cli.train -m experiment=metaworld_v2_table1 model=$model seed=$SEED logger=csv skip_finished=true
done
true
