#!/bin/sh
# The curves of this folder's warm starts (issue 62 item 2) from their committed JSON: curves.png.
#   sh docs/results/warm_start_brownian/scripts/curves.sh     (from the repository root)
set -eu
W=docs/results/warm_start_brownian
python studies/warm_start_curves.py \
  "the paper's loss=$W/arms.json:sampled" "the paper's loss=$W/arms_seed1_500.json:sampled" \
  "the paper's loss=$W/arms_seed2_500.json:sampled" \
  "interpolator reads K̃^e(δ)=$W/arms2.json:tied_interpolator" "interpolator reads K̃^e(δ)=$W/arms_seed1_500.json:tied_interpolator" \
  "interpolator reads K̃^e(δ)=$W/arms_seed2_500.json:tied_interpolator" \
  "expected BCE=$W/arms2.json:expected" "β_ke = 100=$W/arms2.json:beta_ke100" --out $W/curves.png
