#!/bin/sh
# Issue 28, 2026-12-04 (stop 39), core A: TAP trained (pushing Table 1's job) and planned on the 240 tasks
. /work/jobs/sess39_common.sh
date; [ -f $T1/tap_seed0/metrics.json ] || $PY -m keyin.cli.train -m experiment=pushing_table1 model=tap seed=0 trainer.enable_progress_bar=false
plan planner=tap planner.checkpoint=$T1/tap_seed0/checkpoints/tap/last.ckpt
date
