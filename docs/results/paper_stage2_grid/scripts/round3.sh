#!/bin/sh
# Issue 43, round 3 of table=paper_stage2_grid (straight-through δ to 3000 steps; at seeds 0 and 2; the baseline
# at seed 0), one job at a time as keyin-reproduce runs them. Frozen checkout /work/run-tree5 (its keyin/conf a
# link to its conf/); resumable (skip_finished=true).
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 PYTHONPATH=/work/run-tree5
cd /work/run-tree5
PY=/work/main/.venv/bin/python
$PY -m keyin.cli.reproduce table=paper_stage2_grid 'steps=[jobs]' dry_run=true 2>/dev/null | grep '^+ ' | sed 's/^+ python //' |
while read -r cmd; do
  arm=$(echo "$cmd" | sed 's/.*hydra.sweep.subdir=\([^ ]*\).*/\1/')
  case "$arm" in delta_st_3000|delta_st_seed0|delta_st_seed2|baseline_seed0) ;; *) continue ;; esac
  echo "$(date +%T) $arm start"
  eval /usr/bin/time -f "'$arm %e s'" $PY $cmd logger=csv < /dev/null > runs/round3_$arm.log 2>&1
  echo "$(date +%T) $arm done: $(tail -1 runs/round3_$arm.log)"
done
