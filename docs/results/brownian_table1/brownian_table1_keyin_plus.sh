#!/bin/sh
# Issue 24/26: Brownian Table 1, keyin_plus with its priced, leaving teacher (the default since this commit), seeds 1, 2, 0
# (resumable: rerun). Frozen checkout /work/run-tree4 (its runs/ and data/ link to /work/main's).
cd /work/run-tree4
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
exec /work/main/.venv/bin/python -m keyin.cli.train -m experiment=brownian_table1 model=keyin_plus seed=1,2,0
