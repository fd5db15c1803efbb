"""Data-parallel training (DDP) in keyin's terms: which process is rank 0 and each rank's own random
draws (the share of the global batch each rank loads: keyin.data.datamodule.rank_batch_size)."""

from __future__ import annotations

import random

import lightning as L
import numpy as np
import torch
from lightning.pytorch.utilities import rank_zero_only


def is_rank_zero() -> bool:
    """Whether this process is rank 0 (always, without DDP): it alone scores a run and writes its metrics."""
    return rank_zero_only.rank == 0


class RankSeeds(L.Callback):
    """Under DDP, rank r reseeds torch's, numpy's and Python's generators with ``seed + r`` when the fit
    starts, so the ranks draw different segments, frames and noise and the run is still fixed by its
    seed (the weights start equal: DDP copies rank 0's). One process keeps the draws it always had.
    Not ``seed_everything``: it would set ``PL_GLOBAL_SEED``, the seed of the distributed sampler's
    shuffle, which must be one for all ranks or their shares of the data overlap (loader workers
    add the rank to it already)."""

    def __init__(self, seed: int) -> None:
        self.seed = seed

    def on_fit_start(self, trainer: L.Trainer, module: L.LightningModule) -> None:
        if trainer.world_size > 1:
            seed = self.seed + trainer.global_rank
            random.seed(seed)
            np.random.seed(seed)
            torch.manual_seed(seed)
