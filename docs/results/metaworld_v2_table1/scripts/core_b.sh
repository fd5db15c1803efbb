#!/bin/sh
# Issue 46: Meta-World v2 Table 1, the second core's share (see core_a.sh): the untrained rows (3 seeds), Surprise
# (one stage, 3 seeds), then Static seed 0 (waits for core_a.sh's keyin_plus seed 0, whose stage 1 it reads) and
# keyin_plus seed 1 and the other two-stage rows on its stage 1. Two processes never train the same stage 1 at once.
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree9
cd /work/run-tree9
PY=/work/main/.venv/bin/python
$PY -m keyin.cli.train -m experiment=metaworld_v2_table1 model=random,constant,changepoint,changepoint_frames seed=0,1,2 logger=csv skip_finished=true
$PY -m keyin.cli.train -m experiment=metaworld_v2_table1 model=surprise seed=0,1,2 logger=csv skip_finished=true
while pgrep -f "model=keyin_plus,keyin_paper,jumpy seed=0" > /dev/null && [ ! -f runs/multirun/metaworld_v2_table1/keyin_plus_seed0/metrics.json ]; do sleep 60; done
$PY -m keyin.cli.train -m experiment=metaworld_v2_table1 model=static seed=0 logger=csv skip_finished=true
$PY -m keyin.cli.train -m experiment=metaworld_v2_table1 model=keyin_plus seed=1 logger=csv skip_finished=true
$PY -m keyin.cli.train -m experiment=metaworld_v2_table1 model=keyin_paper,jumpy,static seed=1 logger=csv skip_finished=true
$PY -m keyin.cli.eval -m seed=0 ckpt=runs/multirun/metaworld_v2_table1/keyin_plus_seed0/checkpoints/keyframes/last.ckpt "discovery=[segmentation]" skip_finished=true progress=false hydra.sweep.dir=runs/multirun/metaworld_v2_table1 hydra.sweep.subdir=keyin_plus_segmentation_seed0  # stage 1's exact segmentation (the table's eval sweep)
$PY -m keyin.cli.eval -m seed=1 ckpt=runs/multirun/metaworld_v2_table1/keyin_plus_seed1/checkpoints/keyframes/last.ckpt "discovery=[segmentation]" skip_finished=true progress=false hydra.sweep.dir=runs/multirun/metaworld_v2_table1 hydra.sweep.subdir=keyin_plus_segmentation_seed1  # stage 1's exact segmentation (the table's eval sweep)
