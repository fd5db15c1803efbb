"""The LightningDataModule of every dataset: on-the-fly or sharded train clips, fixed val/test."""

from __future__ import annotations

import os
import warnings
from pathlib import Path
from typing import Any, Mapping

import lightning as L
import torch
from torch.utils.data import DataLoader, Dataset, Subset
from torchdata.stateful_dataloader import StatefulDataLoader

from keyin.data.clips import GeneratedClips, ShardClips
from keyin.data.generate import split_seed
from keyin.data.hdf5 import split_files
from keyin.errors import ConfigError, DatasetFormatError


def split_clips(
    dataset: Mapping[str, Any], generator: Any, split: str, size: int | None, data_dir: str | Path
) -> Dataset:
    """One split as a torch Dataset.

    Generated datasets (``train_source: generated``) make clip i of a split from the same seed
    as ``keyin-generate`` does, so on-the-fly clips equal the written shards. Otherwise the split's
    shards are read from ``<data_dir>/<name>/``. Either way ``size`` (None: all) caps the number of
    clips to the split's first ``size``.
    """
    if dataset["train_source"] == "generated":
        total = dataset["splits"][split] if size is None else size
        return GeneratedClips(generator, total, split_seed(dataset["seed"], split), dataset["n_future"])
    files = split_files(Path(data_dir) / dataset["name"], split)
    image = (dataset["image_size"], dataset["image_size"], dataset["channels"])
    clips = ShardClips(files, image, dataset["n_cond"], dataset["n_future"])
    return clips if size is None else Subset(clips, range(min(size, len(clips))))


def rank_batch_size(batch_size: int, world_size: int) -> int:
    """Clips each of ``world_size`` processes loads per step when ``batch_size`` is the global batch
    (``scale.batch_size``, ``scale.stage1_batch_size``), so that a step averages the same number of
    clips on any number of processes.

    Raises:
        ConfigError: the global batch does not split evenly.
    """
    if batch_size % world_size:
        raise ConfigError(
            f"the batch of {batch_size} clips (scale.batch_size / scale.stage1_batch_size, the global batch) does not "
            f"split evenly over {world_size} processes; pick a multiple of {world_size}"
        )
    return batch_size // world_size


class ClipDataModule(L.LightningDataModule):
    """Shuffled training clips (resumable mid-epoch) and a fixed validation set; ``batch_size`` is
    the global batch, which DDP's processes share evenly (:func:`rank_batch_size`)."""

    def __init__(self, train: Dataset, val: Dataset, batch_size: int, num_workers: int) -> None:
        super().__init__()
        if len(train) < batch_size:  # drop_last would leave no batch at all
            raise DatasetFormatError(
                f"the train split has {len(train)} clips, fewer than one batch of {batch_size}; give it "
                f"more (dataset.splits.train=, then `keyin-generate` for file datasets) or lower "
                f"scale.batch_size / scale.stage1_batch_size"
            )
        self.train, self.val = train, val
        self.batch_size, self.num_workers = batch_size, num_workers

    def train_dataloader(self) -> StatefulDataLoader:
        """Shuffled batches from a loader whose position Lightning keeps in every checkpoint, so a
        run resumed mid-epoch continues the epoch's order instead of starting it again."""
        world = self.trainer.world_size if self.trainer else 1
        # Under DDP every rank shuffles alike and Lightning's sampler hands each its share; the ranks'
        # own generators differ (keyin.lit.ranks.RankSeeds), so the order has its own, from the run's seed.
        order = torch.Generator().manual_seed(int(os.environ.get("PL_GLOBAL_SEED", 0))) if world > 1 else None
        with warnings.catch_warnings():  # torchdata 0.11 calls a deprecated torch telemetry hook
            warnings.filterwarnings("ignore", message="'set_vital' is deprecated")
            return StatefulDataLoader(
                self.train,
                batch_size=rank_batch_size(self.batch_size, world),
                shuffle=True,
                generator=order,
                drop_last=True,
                num_workers=self.num_workers,
                persistent_workers=self.num_workers > 0,
            )

    def val_dataloader(self) -> DataLoader:
        return DataLoader(self.val, batch_size=len(self.val), num_workers=0)
