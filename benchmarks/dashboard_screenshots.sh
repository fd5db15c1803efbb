#!/bin/sh
# Pictures of the dashboards a sweep gives: TensorBoard's HParams table (a run per method, its config as
# hyperparameters, test/f1 and the best validation F1 as metrics) and its Scalars, from headless Chromium.
#
#   sh benchmarks/dashboard_screenshots.sh [<sweep dir> or ""] [<out dir>]
#
# Without a sweep dir it makes one in a scratch folder (about 2 minutes on 2 CPU cores): 4 generated test
# clips, then smoke-sized models trained 30 steps per stage, so that the curves have points:
#   keyin-train -m model=keyin,keyin_plus,jumpy,static,surprise scale=smoke logger=tensorboard \
#     scale.stage1_steps=30 scale.stage2_steps=30 scale.surprise_steps=30 scale.val_every=5 scale.checkpoint_every=30
# Writes <out dir>/dashboard_hparams.png and dashboard_scalars.png (default out: docs/img).
# Needs TensorBoard (the track extra) and Chromium (`apt-get install -y chromium`); run as root it passes
# --no-sandbox. Uses port 6006 (PORT=...).
set -eu
BIN=$(cd "$(dirname "$0")/.." && pwd)/.venv/bin
OUT=$(realpath -m "${2:-docs/img}")
PORT=${PORT:-6006}
if [ -n "${1:-}" ]; then
  SWEEP=$(realpath "$1")
else
  SCRATCH=$(mktemp -d)
  (cd "$SCRATCH" && "$BIN/keyin-generate" 'splits={test: 4}' progress=false > /dev/null &&
   "$BIN/keyin-train" -m model=keyin,keyin_plus,jumpy,static,surprise scale=smoke logger=tensorboard \
     scale.stage1_steps=30 scale.stage2_steps=30 scale.surprise_steps=30 scale.val_every=5 scale.checkpoint_every=30 \
     trainer.enable_progress_bar=false > sweep.log 2>&1)
  SWEEP=$(ls -d "$SCRATCH"/runs/multirun/train/*)
fi
echo "sweep: $SWEEP"
"$BIN/tensorboard" --logdir "$SWEEP/tensorboard" --port "$PORT" > /dev/null 2>&1 &
BOARD=$!
trap 'kill $BOARD' EXIT
for _ in $(seq 60); do  # until TensorBoard answers
  "$BIN/python" -c "import urllib.request; urllib.request.urlopen('http://localhost:$PORT')" 2> /dev/null && break
  sleep 1
done
mkdir -p "$OUT"
shoot() {  # shoot <page, with its query> <file>
  chromium --headless --no-sandbox --disable-gpu --disable-quic --no-first-run --disable-background-networking \
    --disable-component-update --disable-sync --user-data-dir="$(mktemp -d)" --window-size=1600,1000 \
    --virtual-time-budget=15000 --screenshot="$OUT/$2" "http://localhost:$PORT/$1" > /dev/null 2>&1
  echo "wrote $OUT/$2"
}
shoot '#hparams' dashboard_hparams.png
# the Scalars page (the Time Series page drew the loss cards empty in headless Chromium, 2026-12-06)
shoot '#scalars&tagFilter=%5E(train%2Floss%7Cval%2Ff1%7Cstage1%2Ftrain%2Floss)%24' dashboard_scalars.png  # ^(train/loss|val/f1|stage1/train/loss)$
