#!/usr/bin/env bash
# The GPU check of issue 60, for a lent GPU machine without network, in under 10 minutes:
#   bash benchmarks/gpu_check.sh            (from the repository root; writes benchmarks/results/gpu_check.md)
# It installs nothing: it runs the machine's own python3 and torch on this source tree (PYTHONPATH=.) and
# generates its own data with keyin-generate. Each step is timed; a failed step is marked and the rest run.
# Steps: a smoke training of both KEYIN stages in fp32 and in bf16-mixed; DDP over every GPU present;
# keyin-eval on the 1000 Brownian test clips and keyin-discover on a long video on the GPU; the training
# step time at scale=cpu and scale=paper (benchmarks/train_step.py).
set -u
cd "$(dirname "$0")/.."
export PYTHONPATH="$PWD${PYTHONPATH:+:$PYTHONPATH}" HYDRA_FULL_ERROR=1
PY=${PYTHON:-python3}
WORK=${WORK:-/tmp/keyin_gpu_check}
OUT=benchmarks/results/gpu_check.md
rm -rf "$WORK" && mkdir -p "$WORK" benchmarks/results
GPUS=$($PY -c 'import torch; print(torch.cuda.device_count())')
ROWS=()

step() {  # step <name> <timeout seconds> <command...>: time one command, keep its log, add a table row
  local name=$1 limit=$2; shift 2
  local log="$WORK/$(echo "$name" | tr -c 'a-zA-Z0-9\n' '_').log" started ended status
  started=$(date +%s%N)
  timeout "$limit" "$@" >"$log" 2>&1; status=$?
  ended=$(date +%s%N)
  local tenths=$(( (ended - started) / 100000000 ))
  local seconds="$((tenths / 10)).$((tenths % 10))"
  local result=ok; [ "$status" -ne 0 ] && result="FAILED (exit $status; last line: $(tail -1 "$log" | cut -c1-120))"
  ROWS+=("| $name | $seconds | $result |")
  echo "$name: $seconds s, $result"
}

keyin() { $PY -m "keyin.cli.$1" "${@:2}"; }
SMOKE=(scale=smoke dataset=brownian logger=none "data_dir=$WORK/data" trainer.enable_progress_bar=false)

step "keyin-generate brownian (1000 test clips)" 120 keyin generate dataset=brownian "data_dir=$WORK/data" 'splits={train: 600, val: 60, test: 1000}'
step "keyin-train smoke, both stages, fp32" 120 keyin train "${SMOKE[@]}" "hydra.run.dir=$WORK/fp32" trainer.precision=32-true
step "keyin-train smoke, both stages, bf16-mixed" 120 keyin train "${SMOKE[@]}" "hydra.run.dir=$WORK/bf16" trainer.precision=bf16-mixed
if [ "$GPUS" -ge 2 ]; then
  step "keyin-train smoke, DDP over $GPUS GPUs" 180 keyin train "${SMOKE[@]}" "hydra.run.dir=$WORK/ddp" trainer=ddp
else
  ROWS+=("| DDP | - | not run: $GPUS GPU(s) |")
fi
step "keyin-eval pretrained:brownian, 1000 test clips, device=cuda" 120 keyin eval ckpt=pretrained:brownian \
  dataset=brownian "data_dir=$WORK/data" device=cuda progress=false "hydra.run.dir=$WORK/eval"
$PY - "$WORK/video.npy" <<'EOF'
import sys, numpy as np
from keyin.data.brownian import BrownianGenerator
arrays, _ = BrownianGenerator(n_cond=1, n_future=17999).generate(0, seed=2026)
np.save(sys.argv[1], arrays["frames"])
EOF
step "keyin-discover 18000-frame video, device=cuda, pictures=false" 180 keyin discover ckpt=pretrained:brownian \
  "input=$WORK/video.npy" fps=30 device=cuda pictures=false progress=false "hydra.run.dir=$WORK/discover"
for scale in cpu paper; do
  step "train_step.py scale=$scale (cuda)" 120 $PY benchmarks/train_step.py --scale "$scale" --steps 5 --device cuda
done

{
  echo "## GPU check (benchmarks/gpu_check.sh)"
  echo
  echo "- machine: $($PY -c 'import torch; print(torch.cuda.get_device_name(0) if torch.cuda.is_available() else "no GPU")') x $GPUS, torch $($PY -c 'import torch; print(torch.__version__)'), $(nproc) CPUs, $(date -I)"
  echo
  echo "| step | wall s | result |"
  echo "|---|---|---|"
  printf '%s\n' "${ROWS[@]}"
  echo
  for run in fp32 bf16 eval discover; do
    [ -f "$WORK/$run/metrics.json" ] && echo "- $run metrics.json: \`$(tr -d '\n' < "$WORK/$run/metrics.json" | cut -c1-400)\`"
  done
  for scale in cpu paper; do  # train_step.py's report: the step times (its profile table follows them in the log)
    log="$WORK/train_step_py_scale_${scale}__cuda_.log"
    [ -f "$log" ] && { echo; echo "### train_step.py --scale $scale --device cuda"; echo; echo '```'; head -30 "$log"; echo '```'; }
  done
} > "$OUT"
echo "wrote $OUT"
