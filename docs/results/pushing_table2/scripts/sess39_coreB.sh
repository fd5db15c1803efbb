#!/bin/sh
# Issue 28, 2026-12-04 (stop 39), core B: No subgoals in the three other servo settings (tasks 0-79)
. /work/jobs/sess39_common.sh
sensitivity planner=no_subgoals
date
