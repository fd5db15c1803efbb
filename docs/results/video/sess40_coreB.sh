#!/bin/sh
# Issue 26, stop 40: Brownian seed 0 of the Table 1 sweep for the video diagnostics on all 1000 test clips:
# the paper's KEYIN (keyin), keyin_plus and Jumpy on one stage 1, then best-of-10 PSNR/SSIM of each.
# Frozen checkout /work/run-tree16 (030086c); resumable (rerun).
cd /work/run-tree16
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl
PY=/work/main/.venv/bin/python
$PY -m keyin.cli.generate dataset=brownian 'splits={val: 1000, test: 1000}'
for m in keyin jumpy keyin_plus; do
  /usr/bin/time -f "$m train %e s" $PY -m keyin.cli.train -m experiment=brownian_table1 model=$m seed=0
done
for m in keyin jumpy keyin_plus; do
  /usr/bin/time -f "$m video %e s" $PY -m keyin.cli.eval ckpt=runs/multirun/brownian_table1/${m}_seed0/checkpoints/keyframes/last.ckpt \
    video_samples=10 'discovery=[offsets]' skip_finished=true progress=false seed=0 hydra.run.dir=runs/long/video_${m}_seed0
done
