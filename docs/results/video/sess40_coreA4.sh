#!/bin/sh
# Stop 40, core A after the paper's KEYIN on pushing_irregular: (issue 26) Brownian seed 2 of the paper's KEYIN and Jumpy with
# their video diagnostics on the 1000 test clips (frozen checkout /work/run-tree16); then (issue 25) Jumpy and Static on the
# frozen-autoencoder stage 1 of pushing_irregular (/work/run-tree17). Resumable.
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl
PY=/work/main/.venv/bin/python
cd /work/run-tree16
for m in keyin jumpy; do
  /usr/bin/time -f "$m seed2 train %e s" $PY -m keyin.cli.train -m experiment=brownian_table1 model=$m seed=2
done
for m in keyin_paper jumpy; do
  /usr/bin/time -f "$m seed2 video %e s" $PY -m keyin.cli.eval ckpt=runs/multirun/brownian_table1/${m}_seed2/checkpoints/keyframes/last.ckpt \
    video_samples=10 'discovery=[offsets]' skip_finished=true progress=false seed=2 hydra.run.dir=runs/long/video_${m}_seed2
done
cd /work/run-tree17
AE=/work/run-tree15/runs/frames/pushing_w8_s6000/checkpoints/frames/last.ckpt
for m in jumpy static; do
  /usr/bin/time -f "$m irregular frames %e s" $PY -m keyin.cli.train -m experiment=pushing_irregular_table1 backbone=frames \
    backbone.frames_ckpt=$AE name=pushing_irregular_frames stage1_dir=runs/frames_stage1/pushing_irregular model=$m seed=0
done
