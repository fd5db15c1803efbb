#!/bin/sh
# Restart the stated configuration's background jobs at the start of a session (issue 62): for each line of jobs.txt, a
# frozen checkout of the commit the job started with, a venv that borrows the main checkout's packages, the job's carried
# checkpoint put back (carry.py restore, when the machine was replaced), then this checkout's scripts/<kind>.sh resumed in
# the background (a finished or paused job: its checkpoint put back only).
#   sh docs/results/keyin_paper_stated/scripts/restart.sh [<jobs dir>]     (from the main checkout, .venv installed)
# THREADS=2 in its environment gives each job it resumes two torch threads (one job alone on the 2-core machine).
set -eu
main=$(git rev-parse --show-toplevel)
jobs=${1:-/work/jobs}
scripts="$main/docs/results/keyin_paper_stated/scripts"
mkdir -p "$jobs"
"$main/.venv/bin/keyin-generate" dataset=brownian 'splits={val: 1000, test: 1000}' data_dir="$main/data" > /dev/null  # skips finished shards
grep -v '^#' "$scripts/jobs.txt" | while read -r kind frozen commit job seed more; do
  case $job in *stage2*) stage=keyframes ;; *) stage=interpolator ;; esac  # a finished or paused job too
  # its run dir ends the command line (stage2.sh) or an override follows it (stage1.sh); not a longer job's (..._20k)
  if pgrep -f "hydra.run.dir=$jobs/$job( |\$)" > /dev/null; then echo "$job is running already"; continue; fi
  "$main/.venv/bin/python" "$scripts/carry.py" restore "$jobs" "$job" --stage "$stage"
  case $kind in
    finished) echo "$job is finished: its checkpoint is in place"; continue ;;
    paused) echo "$job is paused: its checkpoint is in place (kind stage1/stage2 in jobs.txt resumes it)"; continue ;;
  esac
  [ -d "$frozen" ] || git -C "$main" worktree add --detach "$frozen" "$commit"
  if [ ! -x "$frozen/.venv/bin/keyin-train" ]; then
    python3 -m venv "$frozen/.venv"
    site=$("$main/.venv/bin/python" -c 'import site; print(site.getsitepackages()[0])')
    echo "$site" > "$("$frozen/.venv/bin/python" -c 'import site; print(site.getsitepackages()[0])')/main_deps.pth"
    "$frozen/.venv/bin/pip" install -q --no-deps -e "$frozen"
  fi
  [ -e "$frozen/data" ] || ln -s "$main/data" "$frozen/data"
  case $kind in
    stage1) set -- "$seed" "$jobs" "$main/data" "$job" ;;
    stage2) set -- "$seed" "$more" "$jobs" "$main/data"; more= ;;
    *) echo "jobs.txt: unknown kind $kind for $job (stage1, stage2, finished or paused)" >&2; exit 1 ;;
  esac
  # shellcheck disable=SC2086  # the overrides are words
  (cd "$frozen" && PATH="$frozen/.venv/bin:$PATH" nohup sh "$scripts/$kind.sh" "$@" $more >> "$jobs/${job}_$kind.log" 2>&1 &)
  echo "$job resumed in the background in $frozen; log: $jobs/${job}_$kind.log"
done
