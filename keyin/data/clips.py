"""Torch datasets of clips: generated on the fly, or read lazily from HDF5 shards.

Every item is a dict:

* ``frames`` float32 (L, C, H, W) in [0, 1], L = n_cond + n_future;
* ``future_length`` int64 (): valid future frames n_b <= n_future (the rest repeats the last frame);
* ``keyframes`` bool (n_future,): ground-truth keyframes on the future axis (all False if unknown).
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import h5py
import numpy as np
import torch
from torch.utils.data import Dataset

from keyin.data.hdf5 import ShardInfo, check_compatible, check_frame_values, inspect_shard
from keyin.errors import DatasetFormatError


def clip_item(arrays: dict[str, np.ndarray], n_cond: int, n_future: int) -> dict[str, torch.Tensor]:
    """Turn one clip's stored arrays into a training item (see the module docstring)."""
    clip_length = n_cond + n_future
    frames = torch.from_numpy(np.ascontiguousarray(arrays["frames"][:clip_length]))
    frames = frames.permute(0, 3, 1, 2).float().div_(255.0)
    return {"frames": frames, **future_labels(int(arrays["length"]), arrays.get("keyframes"), n_cond, n_future)}


def future_labels(length: int, keyframes: np.ndarray | None, n_cond: int, n_future: int) -> dict[str, torch.Tensor]:
    """A clip's ``future_length`` and future ``keyframes`` (see the module docstring) from its stored
    valid length and keyframes (L,) on the clip's own axis (None: unknown)."""
    future_length = int(min(length - n_cond, n_future))
    future_keys = (
        torch.zeros(n_future, dtype=torch.bool)
        if keyframes is None
        else torch.from_numpy(np.array(keyframes[n_cond : n_cond + n_future], dtype=bool))  # a copy
    )
    future_keys[max(future_length, 0) :] = False
    return {"future_length": torch.tensor(future_length, dtype=torch.int64), "keyframes": future_keys}


class GeneratedClips(Dataset):
    """Clips made on the fly by a generator; item i depends only on ``seed + i``."""

    def __init__(self, generator, size: int, seed: int, n_future: int) -> None:
        self.generator, self.size, self.seed, self.n_future = generator, size, seed, n_future

    def __len__(self) -> int:
        return self.size

    def __getitem__(self, index: int) -> dict[str, torch.Tensor]:
        arrays, _ = self.generator.generate(index, self.seed)
        return clip_item(arrays, self.generator.n_cond, self.n_future)


class ShardClips(Dataset):
    """Clips read lazily from validated HDF5 shards; each worker opens its own file handles.

    Every command that reads keyin's HDF5 (keyin-eval, -train, -figures, -report; ``data=`` files and
    dataset folders alike) reads it here, so the layout, the sizes and a sample of each shard's values
    are checked here, before any model sees a frame.
    """

    def __init__(
        self,
        paths: Sequence[Path],
        image_shape: tuple[int, int, int],
        n_cond: int,
        n_future: int,
    ) -> None:
        self.infos: list[ShardInfo] = [inspect_shard(Path(p)) for p in paths]
        for info in self.infos:
            check_compatible(info, image_shape, n_cond, n_future)
        check_frame_values(self.infos)
        self.n_cond, self.n_future = n_cond, n_future
        self.offsets = np.cumsum([0] + [info.n for info in self.infos])
        if self.offsets[-1] == 0:
            raise DatasetFormatError(
                f"no clips in {', '.join(str(p) for p in paths) or 'an empty file list'}; pass a file "
                f"with clips or generate some with `keyin-generate` (e.g. splits='{{test: 1000}}')"
            )
        self._handles: dict[int, h5py.File] = {}

    def __len__(self) -> int:
        return int(self.offsets[-1])

    def _handle(self, shard: int) -> h5py.File:
        if shard not in self._handles:
            self._handles[shard] = h5py.File(self.infos[shard].path, "r")
        return self._handles[shard]

    def __getitem__(self, index: int) -> dict[str, torch.Tensor]:
        if not 0 <= index < len(self):
            raise IndexError(index)
        shard = int(np.searchsorted(self.offsets, index, side="right") - 1)
        row = index - int(self.offsets[shard])
        handle = self._handle(shard)
        names = ("frames", "length", "keyframes")
        arrays = {name: handle[name][row] for name in names if name in handle}
        return clip_item(arrays, self.n_cond, self.n_future)

    def __getstate__(self) -> dict:
        state = dict(self.__dict__)
        state["_handles"] = {}
        return state
