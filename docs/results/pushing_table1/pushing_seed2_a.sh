#!/bin/sh
# Issue 24: pushing Table 1 seed 2, first core: keyin_plus (trains the seed's shared stage 1), then Jumpy,
# the paper's KEYIN and keyin_evidence (offset evidence alone, one seed: seed 2) on that stage 1.
# Resumable: rerun; finished jobs are skipped. Frozen checkout /work/run-tree7 (runs/, data/ link to /work/main's).
cd /work/run-tree7
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl
while pgrep -f "keyin-generate dataset=pushing" > /dev/null; do sleep 20; done
exec /work/main/.venv/bin/python -m keyin.cli.train -m experiment=pushing_table1 model=keyin_plus,jumpy,keyin,keyin_evidence seed=2
