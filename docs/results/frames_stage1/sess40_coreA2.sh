#!/bin/sh
# Issue 25, stop 40: the same on dataset=pushing_irregular (the pushing autoencoder, frozen), its gates on
# 200 validation clips beside Constant's and Random's keyframes there. Frozen checkout /work/run-tree17; resumable.
cd /work/run-tree17
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree17
PY=/work/main/.venv/bin/python
AE=/work/run-tree15/runs/frames/pushing_w8_s6000/checkpoints/frames/last.ckpt
RUN=runs/frames_stage1/pushing_irregular
/usr/bin/time -f "stage1 irregular %e s" $PY -m keyin.cli.train model=keyin_plus dataset=pushing_irregular backbone=frames \
  backbone.frames_ckpt=$AE stage=interpolator hydra.run.dir=$RUN
/usr/bin/time -f "gate irregular %e s" $PY -m keyin.cli.eval ckpt=$RUN/checkpoints/interpolator/last.ckpt dataset=pushing_irregular \
  split=val clips=200 progress=false hydra.run.dir=runs/frames_stage1/gate_pushing_irregular
$PY studies/stage1_objects.py $RUN/checkpoints/interpolator/last.ckpt --split val --clips 200 > runs/frames_stage1/objects_pushing_irregular.md
for m in constant random; do
  $PY -m keyin.cli.eval model=$m dataset=pushing_irregular split=val clips=200 progress=false hydra.run.dir=runs/frames_stage1/${m}_pushing_irregular_val
done
