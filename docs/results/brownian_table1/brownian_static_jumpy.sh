#!/bin/sh
# Issue 24: Brownian Table 1's Static row (seeds 0, 2, 1) and Jumpy seeds 0, 2 (resumable: rerun; finished jobs are skipped).
# Frozen checkout /work/run-tree6 (its runs/ and data/ link to /work/main's). Static and Jumpy share stage 1 per seed.
cd /work/run-tree6
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
/work/main/.venv/bin/python -m keyin.cli.train -m experiment=brownian_table1 model=static,jumpy seed=0,2
exec /work/main/.venv/bin/python -m keyin.cli.train -m experiment=brownian_table1 model=static seed=1
