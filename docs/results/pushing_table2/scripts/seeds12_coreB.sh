#!/bin/sh
# Issue 28, 2026-12-03 (stop 37), core B: Jumpy seed 2 (its own stage 1), keyin_paper seed 2 on it and its plan, then keyin_plus seed 2
. /work/jobs/seeds12_common.sh
train jumpy 2
train keyin_paper 2
plan 2 planner=keyin planner.model=keyin_paper
train keyin_plus 2
date
