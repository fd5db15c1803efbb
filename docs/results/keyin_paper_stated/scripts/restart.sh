#!/bin/sh
# Restart the stated configuration's jobs at the start of a session (issue 62): a frozen checkout of the commit the jobs
# started with, a venv that borrows the main checkout's packages, then stage 1 of seed 0 resumed in the background from
# <jobs>/stated_seed0/checkpoints/interpolator/last.ckpt, put there from models/in_progress/ by carry.py when the machine
# was replaced (a fresh start if nothing was carried).
#   sh docs/results/keyin_paper_stated/scripts/restart.sh [<jobs dir> [<frozen dir>]]     (from the main checkout, .venv installed)
set -eu
main=$(git rev-parse --show-toplevel)
jobs=${1:-/work/jobs}
frozen=${2:-/work/frozen62}
commit=93cb072  # the code stage 1 of seed 0 started with (2026-12-06)
mkdir -p "$jobs"
[ -d "$frozen" ] || git -C "$main" worktree add --detach "$frozen" "$commit"
if [ ! -x "$frozen/.venv/bin/keyin-train" ]; then
  python3 -m venv "$frozen/.venv"
  site=$("$main/.venv/bin/python" -c 'import site; print(site.getsitepackages()[0])')
  echo "$site" > "$("$frozen/.venv/bin/python" -c 'import site; print(site.getsitepackages()[0])')/main_deps.pth"
  "$frozen/.venv/bin/pip" install -q --no-deps -e "$frozen"
fi
[ -e "$frozen/data" ] || ln -s "$main/data" "$frozen/data"
"$main/.venv/bin/keyin-generate" dataset=brownian 'splits={val: 1000, test: 1000}' data_dir="$main/data" > /dev/null  # skips finished shards
"$main/.venv/bin/python" "$main/docs/results/keyin_paper_stated/scripts/carry.py" restore "$jobs" stated_seed0
cd "$frozen"
PATH="$frozen/.venv/bin:$PATH" nohup sh docs/results/keyin_paper_stated/scripts/stage1.sh 0 "$jobs" "$main/data" \
  >> "$jobs/stated_seed0_stage1.log" 2>&1 &
echo "stage 1 of seed 0 resumed in the background (pid $!); log: $jobs/stated_seed0_stage1.log"
