#!/bin/sh
# Issue 46: Meta-World v2 Table 1, the first core's share (frozen checkout /work/run-tree9, its keyin/conf a link
# to its conf/, data/metaworld_v2 a link to the generated set). Seed 0's two-stage rows first (keyin_plus trains
# the stage 1 that keyin_paper and jumpy share), then keyin_plus seed 2 and the other two-stage rows on its stage 1.
# Resumable: skip_finished, last.ckpt.
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree9
cd /work/run-tree9
PY=/work/main/.venv/bin/python
$PY -m keyin.cli.train -m experiment=metaworld_v2_table1 model=keyin_plus,keyin_paper,jumpy seed=0 logger=csv skip_finished=true
$PY -m keyin.cli.train -m experiment=metaworld_v2_table1 model=keyin_plus seed=2 logger=csv skip_finished=true
$PY -m keyin.cli.train -m experiment=metaworld_v2_table1 model=keyin_paper,jumpy,static seed=2 logger=csv skip_finished=true
$PY -m keyin.cli.eval -m seed=2 ckpt=runs/multirun/metaworld_v2_table1/keyin_plus_seed2/checkpoints/keyframes/last.ckpt "discovery=[segmentation]" skip_finished=true progress=false hydra.sweep.dir=runs/multirun/metaworld_v2_table1 hydra.sweep.subdir=keyin_plus_segmentation_seed2  # stage 1's exact segmentation (the table's eval sweep)
