#!/bin/sh
# Issue 43: a stochastic Brownian stage 1 (Zi = 8, paper's seq2seq-VAE interpolator), backbone=ours, seed 1 (the seed of pretrained:brownian's stage 1)
export OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 PYTHONPATH=/work/run-tree
cd /work/run-tree
/usr/bin/time -f "stage1 z8 %e s" /work/main/.venv/bin/python -m keyin.cli.train experiment=brownian_table1 model=keyin_paper \
  stage=interpolator scale.inter_latent=8 seed=1 stage1_dir=runs/grid/stage1_ours_z8_seed1 hydra.run.dir=runs/grid/stage1_ours_z8_seed1 evaluate=false
