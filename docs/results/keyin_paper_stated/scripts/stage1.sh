#!/bin/sh
# The stated configuration's stage 1 (issue 62), one seed per call, resumable: run it again with the
# same arguments and it continues from <jobs>/stated_seed<seed>/checkpoints/interpolator/last.ckpt.
#   sh docs/results/keyin_paper_stated/scripts/stage1.sh <seed> <jobs dir> <data dir>
set -eu
seed=$1; jobs=$2; data=$3
OMP_NUM_THREADS=1 exec keyin-train experiment=brownian_keyin_stated stage=interpolator seed="$seed" \
  data_dir="$data" hydra.run.dir="$jobs/stated_seed$seed" evaluate=false
