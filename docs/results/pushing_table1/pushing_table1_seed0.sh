#!/bin/sh
# Issue 24/25/27: pushing Table 1, seed 0 over every row (resumable: rerun; finished jobs are skipped).
# Frozen checkout /work/run-tree5 (its runs/ and data/ link to /work/main's).
cd /work/run-tree5
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
exec /work/main/.venv/bin/python -m keyin.cli.train -m experiment=pushing_table1 model=keyin_plus,keyin,jumpy,static,random,constant,changepoint,changepoint_frames,surprise seed=0
