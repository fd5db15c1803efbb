export OMP_NUM_THREADS=1 MUJOCO_GL=egl PYTHONPATH=/work/run-tree6
PY=/work/main/.venv/bin/python
$PY -m keyin.cli.generate dataset=metaworld workers=1 'splits={val: 300, test: 500}'
$PY -m keyin.cli.generate dataset=metaworld workers=1
