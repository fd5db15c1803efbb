#!/bin/sh
# Issue 28, 2026-12-03 (stop 38), core A after sess38_coreA.sh (pid $1): keyin_paper's model 0 under planning seeds 1, 2
# (from /work/run-tree13: keyin-plan records the model seed there), then TAP trained (pushing Table 1's job) and planned
. /work/jobs/sess38_common.sh
cd /work/run-tree13
while kill -0 $1 2>/dev/null; do sleep 30; done
plan planner=keyin planner.model=keyin_paper planner.model_seed=0 seed=1,2 "$CKPT" 'hydra.sweep.subdir=${planner.name}_model${planner.model_seed}_seed${seed}'
date; [ -f $T1/tap_seed0/metrics.json ] || $PY -m keyin.cli.train -m experiment=pushing_table1 model=tap seed=0 trainer.enable_progress_bar=false
plan planner=tap planner.checkpoint=$T1/tap_seed0/checkpoints/tap/last.ckpt
date
