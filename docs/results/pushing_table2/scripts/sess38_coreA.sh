#!/bin/sh
# Issue 28, 2026-12-03 (stop 38), core A: keyin_plus seed 2's plan, then the servo settings of keyin_paper and Jumpy (model seed 0)
. /work/jobs/sess38_common.sh
plan planner=keyin seed=2 "$CKPT"
sensitivity planner=keyin planner.model=keyin_paper "$CKPT"
sensitivity planner=jumpy "$CKPT"
date
