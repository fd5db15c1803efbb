#!/bin/sh
# core B: keyin_paper seed 0 (the paper's method), then Jumpy seed 1
. /work/jobs/plan_common.sh
wait_for $T1/keyin_paper_seed0/metrics.json
export_job keyin_paper_seed0
plan 0 planner=keyin planner.model=keyin_paper
wait_for $MODELS/jumpy_seed1.ckpt
sleep 5
plan 1 planner=jumpy
date
