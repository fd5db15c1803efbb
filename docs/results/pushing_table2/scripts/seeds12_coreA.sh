#!/bin/sh
# Issue 28, 2026-12-03 (stop 37), core A: keyin_paper seed 1 (on stage1_ours_seed1), its plan, Jumpy seed 2's plan, then keyin_plus seed 1's remaining tasks
. /work/jobs/seeds12_common.sh
train keyin_paper 1
plan 1 planner=keyin planner.model=keyin_paper
wait_for $MODELS/jumpy_seed2.ckpt
plan 2 planner=jumpy
plan 1 planner=keyin
date
