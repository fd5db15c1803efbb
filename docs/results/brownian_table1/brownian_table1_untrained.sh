#!/bin/sh
# Issue 24: Brownian Table 1, the methods that train nothing (random, constant, change-point on the centroid
# signal and on the frames), seeds 0-2 (resumable: rerun). Frozen checkout /work/run-tree4.
# Re-run on 2026-12-06 on main (the ±2 F1 column): exact scores identical; the jobs' metrics.json are that run's.
cd /work/run-tree4
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
exec /work/main/.venv/bin/python -m keyin.cli.train -m experiment=brownian_table1 model=random,constant,changepoint,changepoint_frames seed=0,1,2
