#!/bin/sh
# The curves of this folder's warm starts (issue 62 item 2, the stated configuration's own stage 1): curves.png.
#   sh docs/results/warm_start_stated/scripts/curves.sh     (from the repository root)
set -eu
W=docs/results/warm_start_stated
python studies/warm_start_curves.py \
  "placed 1500 steps on the labels, then released (finished stage 1), seed 0=$W/placed_supervised_1500_seed0.json:placed_supervised_1500" \
  "the same, seed 1=$W/placed_supervised_1500_seed1.json:placed_supervised_1500" \
  "the same, seed 2=$W/placed_supervised_1500_seed2.json:placed_supervised_1500" \
  "placed 300 steps, labels + the paper's loss (stage 1 at 2k)=$W/ws_placed_seed0.json:placed" --out $W/curves.png
