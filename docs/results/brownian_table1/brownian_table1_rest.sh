#!/bin/sh
# Issue 24: the Brownian Table 1 rows still to run (resumable: rerun; finished jobs are skipped). Frozen checkout /work/run-tree4.
cd /work/run-tree4
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
exec /work/main/.venv/bin/python -m keyin.cli.train -m experiment=brownian_table1 model=keyin,static,surprise seed=2,0,1
