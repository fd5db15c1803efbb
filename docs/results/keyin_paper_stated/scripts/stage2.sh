#!/bin/sh
# The stated configuration's stage 2 (issue 62), one seed per call, on the finished stage 1 of seed 0 (shared by every
# seed: one stage 1 costs ~5 CPU-hours here), resumable: run it again with the same arguments and it continues from
# <jobs>/stated_stage2_seed<seed>/checkpoints/keyframes/last.ckpt. The row is named by its budget: 10k stage-1 steps and
# <steps> stage-2 steps (keyin_paper_stated_10k_<steps/1000>k); at the end it scores the 1000 test clips. The row's
# seeds run 5000 steps (job stated_stage2_seed<seed>); a longer budget (item 4's curve, job
# stated_stage2_seed<seed>_<steps/1000>k) goes on from that job's finished checkpoint (carry.py extend).
#   sh docs/results/keyin_paper_stated/scripts/stage2.sh <seed> <steps> <jobs dir> <data dir>
# THREADS=<n> (default 1) sets its torch threads: 2 where it has the machine's two cores to itself.
set -eu
seed=$1; steps=$2; jobs=$3; data=$4
job=stated_stage2_seed$seed; model=keyin_paper_stated_10k_$((steps / 1000))k
if [ "$steps" != 5000 ]; then
  job=${job}_$((steps / 1000))k
  python "$(dirname "$0")/carry.py" extend "$jobs" "$job" --stage keyframes --from "stated_stage2_seed$seed" --model "$model"
fi
stage1="$jobs/stated_seed0/checkpoints/interpolator/last.ckpt"
python -c "import sys, torch; step = torch.load(sys.argv[1], map_location='cpu', weights_only=False)['global_step']
sys.exit(0 if step >= 10000 else f'{sys.argv[1]} is at step {step} of 10000: finish stage 1 first (stage1.sh 0 ...)')" "$stage1"
OMP_NUM_THREADS=${THREADS:-1} exec keyin-train experiment=brownian_keyin_stated stage=keyframes seed="$seed" \
  interpolator_ckpt="$stage1" scale.stage2_steps="$steps" model.name="$model" \
  data_dir="$data" hydra.run.dir="$jobs/$job"
