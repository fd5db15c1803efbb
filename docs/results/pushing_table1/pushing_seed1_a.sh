#!/bin/sh
# Issue 24/28: pushing Table 1 seed 1, reordered for the session's time: keyin_plus seed 1 was scored by
# pushing_seed1.sh; then Jumpy and the paper's KEYIN (resumable; finished jobs skipped).
cd /work/run-tree6
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1
exec /work/main/.venv/bin/python -m keyin.cli.train -m experiment=pushing_table1 model=jumpy,keyin seed=1
