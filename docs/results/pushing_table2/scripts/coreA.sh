#!/bin/sh
# Issue 28, 2026-12-03: run from the frozen checkout /work/run-tree9 (its runs/ and data/ link to /work/main's), one core
# core A: data (both cores), then keyin_plus seed 1 (its stage 1) and jumpy seed 1 on that stage 1
cd /work/run-tree9
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl
PY=/work/main/.venv/bin/python
date; $PY -m keyin.cli.generate dataset=pushing workers=2 progress=false && touch /work/jobs/data.done
date; $PY -m keyin.cli.train -m experiment=pushing_table1 model=keyin_plus seed=1 trainer.enable_progress_bar=false
date; $PY -m keyin.cli.train -m experiment=pushing_table1 model=jumpy seed=1 trainer.enable_progress_bar=false
date
