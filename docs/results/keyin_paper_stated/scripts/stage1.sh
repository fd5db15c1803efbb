#!/bin/sh
# The stated configuration's stage 1 (issue 62), one seed per call, resumable: run it again with the same arguments and it
# continues from <jobs>/<job>/checkpoints/interpolator/last.ckpt. <job> defaults to stated_seed<seed>; a variant names its
# own job and adds its overrides (e.g. stated_klmean_seed0 loss.inter_kl=5.12 model.name=keyin_paper_stated_klmean_20k).
#   sh docs/results/keyin_paper_stated/scripts/stage1.sh <seed> <jobs dir> <data dir> [<job> <override>...]
set -eu
seed=$1; jobs=$2; data=$3; shift 3
job=${1:-stated_seed$seed}; [ $# -gt 0 ] && shift
OMP_NUM_THREADS=1 exec keyin-train experiment=brownian_keyin_stated stage=interpolator seed="$seed" \
  data_dir="$data" hydra.run.dir="$jobs/$job" evaluate=false "$@"
