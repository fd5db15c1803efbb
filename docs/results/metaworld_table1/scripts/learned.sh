#!/bin/sh
# Issue 46: Table 1's learned rows on Meta-World, seed 0 first (keyin_plus, keyin_paper, jumpy, static share a
# stage 1), then seeds 1-2; frozen checkout /work/run-tree7 (its keyin/conf a link to its conf/); resumable.
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree7
cd /work/run-tree7
while pgrep -f "keyin.cli.generate dataset=metaworld" > /dev/null; do sleep 30; done
for s in 0 1 2; do
  /work/main/.venv/bin/python -m keyin.cli.train -m experiment=metaworld_table1 model=keyin_plus,keyin_paper,jumpy,static,surprise seed=$s logger=csv
done
