#!/bin/sh
# Issue 46: Meta-World version 2's data and the choices made on its val clips before its Table 1 runs
# (conf/dataset/metaworld_v2.yaml). Run from a frozen checkout with one torch thread per process:
#   git worktree add --detach /work/run-tree8 HEAD && ln -s ../conf /work/run-tree8/keyin/conf
#   cd /work/run-tree8 && sh docs/results/metaworld_v2_table1/scripts/prepare.sh
# Resumable: keyin-generate keeps finished shards; each step writes its result file under benchmarks/results/.
set -e
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=$(pwd)
PY=${PY:-/work/main/.venv/bin/python}
WORKERS=${WORKERS:-1}
$PY -m keyin.cli.generate dataset=metaworld_v2 workers=$WORKERS progress=false
$PY benchmarks/metaworld_stats.py --dataset metaworld_v2 --split val --out benchmarks/results/metaworld_v2_stats.md
$PY benchmarks/choose_constant.py --dataset metaworld_v2 --clips 300 --split val --out benchmarks/results/choose_constant_metaworld_v2.md
$PY benchmarks/choose_constant.py --dataset metaworld_v2 --clips 300 --split val --first-m --out benchmarks/results/choose_constant_metaworld_v2_first_m.md
$PY benchmarks/choose_changepoint.py --dataset metaworld_v2 --clips 300 --split val --signals pixels differences centroid_velocity --costs l2 rbf --out benchmarks/results/choose_changepoint_metaworld_v2.md
