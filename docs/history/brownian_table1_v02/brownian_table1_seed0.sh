#!/bin/sh
# Issue 24: Brownian Table 1, the paper's KEYIN (model=keyin) and KEYIN with our additions, seed 0 (resumable: rerun).
# Runs in the frozen checkout /work/run-tree2 (its runs/ and data/ link to /work/main's), so that edits in
# /work/main reach no running sweep (a sweep composes each job's config from the package on disk).
cd /work/run-tree2
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
exec /work/main/.venv/bin/python -m keyin.cli.train -m experiment=brownian_table1 model=keyin,keyin_plus seed=0
