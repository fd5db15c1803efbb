#!/bin/sh
# Beside the 20k-step run (issue 26): Jumpy seed 1 on the Table 1 sweep's stage 1 of seed 1 (for the best-of-10
# PSNR of KEYIN vs Jumpy and Fig. 4), then their video diagnostics on the first 200 test clips, then the paper's
# KEYIN seed 1 of Table 1. Frozen checkout /work/run-tree4; resumable (rerun).
# (started beside it at 22:58, when a third process kept both cores busy to the end of the session)
cd /work/run-tree4
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
PY=/work/main/.venv/bin/python
$PY -m keyin.cli.train -m experiment=brownian_table1 model=jumpy seed=1
cd /work/main   # keyin-eval clips= is newer than run-tree4
for m in keyin_plus jumpy; do
  $PY -m keyin.cli.eval ckpt=runs/multirun/brownian_table1/${m}_seed1/checkpoints/keyframes/last.ckpt video_samples=10 \
    clips=200 discovery=[offsets] skip_finished=true progress=false seed=1 hydra.run.dir=runs/long/video_${m}_seed1
done
cd /work/run-tree4
$PY -m keyin.cli.train -m experiment=brownian_table1 model=keyin seed=1
