#!/bin/sh
# core A: Jumpy seed 0 (pairs with the planned keyin_plus seed 0), then keyin_plus seed 1
. /work/jobs/plan_common.sh
wait_for $T1/jumpy_seed1/metrics.json      # core A's trainings done (jumpy_seed0 long before)
export_job jumpy_seed0; export_job keyin_plus_seed1; export_job jumpy_seed1
plan 0 planner=jumpy
plan 1 planner=keyin
date
