#!/bin/sh
# Stop 40, core B after the Brownian video jobs: (issue 25) the change-point baseline's signal, cost and penalty chosen on
# 300 validation clips of pushing_irregular, as on pushing; then (issue 26) Brownian seed 1 of the paper's KEYIN and Jumpy
# with their video diagnostics on the 1000 test clips. Frozen checkout /work/run-tree16 (updated to main); resumable.
cd /work/run-tree16
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree16
PY=/work/main/.venv/bin/python
/usr/bin/time -f "keyin_paper video %e s" $PY -m keyin.cli.eval ckpt=runs/multirun/brownian_table1/keyin_paper_seed0/checkpoints/keyframes/last.ckpt \
  video_samples=10 'discovery=[offsets]' skip_finished=true progress=false seed=0 hydra.run.dir=runs/long/video_keyin_paper_seed0
$PY benchmarks/choose_changepoint.py --dataset pushing_irregular --clips 300 --split val --signals pixels differences centroid_velocity \
  --costs l2 rbf --out benchmarks/results/choose_changepoint_pushing_irregular.md
for m in keyin jumpy; do
  /usr/bin/time -f "$m seed1 train %e s" $PY -m keyin.cli.train -m experiment=brownian_table1 model=$m seed=1
done
for m in keyin_paper jumpy; do
  /usr/bin/time -f "$m seed1 video %e s" $PY -m keyin.cli.eval ckpt=runs/multirun/brownian_table1/${m}_seed1/checkpoints/keyframes/last.ckpt \
    video_samples=10 'discovery=[offsets]' skip_finished=true progress=false seed=1 hydra.run.dir=runs/long/video_${m}_seed1
done
