#!/bin/sh
# Issue 28, 2026-12-03 (stop 38), core B: No subgoals (240 tasks), then Surprise (SVG's skips) trained and planned
. /work/jobs/sess38_common.sh
plan planner=no_subgoals
date; [ -f $T1/surprise_skips_seed0/metrics.json ] || $PY -m keyin.cli.train -m experiment=pushing_table1 model=surprise seed=0 model.module.skips=true hydra.sweep.subdir=surprise_skips_seed0 trainer.enable_progress_bar=false
plan planner=surprise planner.checkpoint=$T1/surprise_skips_seed0/checkpoints/surprise/last.ckpt
date
