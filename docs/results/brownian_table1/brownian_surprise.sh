#!/bin/sh
# Issue 24: Brownian Table 1's Surprise row, seeds 0-2 (resumable: rerun). Frozen checkout /work/run-tree5.
cd /work/run-tree5
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
exec /work/main/.venv/bin/python -m keyin.cli.train -m experiment=brownian_table1 model=surprise seed=0,1,2
