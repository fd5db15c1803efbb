#!/bin/sh
# Issue 28, 2026-12-03 (stop 38), core A after sess38_coreA.sh: TAP trained (pushing Table 1's job) and planned
. /work/jobs/sess38_common.sh
while kill -0 $1 2>/dev/null; do sleep 30; done
date; [ -f $T1/tap_seed0/metrics.json ] || $PY -m keyin.cli.train -m experiment=pushing_table1 model=tap seed=0 trainer.enable_progress_bar=false
plan planner=tap planner.checkpoint=$T1/tap_seed0/checkpoints/tap/last.ckpt
date
