#!/bin/sh
# Issue 28, 2026-12-03: run from the frozen checkout /work/run-tree9 (its runs/ and data/ link to /work/main's), one core
# core B: after the data, jumpy seed 0 (its own stage 1), then keyin_paper seed 0 on that stage 1
cd /work/run-tree9
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl
PY=/work/main/.venv/bin/python
while [ ! -f /work/jobs/data.done ]; do sleep 20; done
date; $PY -m keyin.cli.train -m experiment=pushing_table1 model=jumpy seed=0 trainer.enable_progress_bar=false
date; $PY -m keyin.cli.train -m experiment=pushing_table1 model=keyin seed=0 trainer.enable_progress_bar=false
date
