#!/bin/sh
# Issue 43: the rows of table=paper_stage2_grid, as keyin-reproduce would run them, shared by two workers
# (each claims the next unclaimed sweep: mkdir is atomic). Frozen checkout /work/run-tree3; resumable
# (a claimed but unfinished sweep is resumed by a worker started with RESUME=1). Usage: grid.sh
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 PYTHONPATH=/work/run-tree3
cd /work/run-tree3
PY=/work/main/.venv/bin/python
CLAIMS=runs/multirun/paper_stage2_grid/.claims; mkdir -p $CLAIMS
$PY -m keyin.cli.reproduce table=paper_stage2_grid 'steps=[jobs]' dry_run=true 2>/dev/null | grep '^+ ' | sed 's/^+ python //' |
while read -r cmd; do
  arm=$(echo "$cmd" | sed 's/.*hydra.sweep.subdir=\([^ ]*\).*/\1/')
  case "$ONLY" in ""|*" $arm "*) ;; *) continue ;; esac
  [ -f runs/multirun/paper_stage2_grid/$arm/metrics.json ] && continue
  [ -d runs/multirun/paper_stage2_grid/$arm/checkpoints/interpolator ] && [ "$arm" != "${arm#stage1}" ] && [ ! -f runs/multirun/paper_stage2_grid/$arm/checkpoints/interpolator/last.ckpt ] && continue
  mkdir $CLAIMS/$arm 2>/dev/null || [ "$RESUME" = 1 ] || continue
  echo "$(date +%T) $arm start"
  /usr/bin/time -f "$arm %e s" $PY $cmd < /dev/null > $CLAIMS/$arm.log 2>&1
  echo "$(date +%T) $arm done: $(tail -1 $CLAIMS/$arm.log)"
done
