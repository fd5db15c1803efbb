"""A dataset's frames encoded once by a frozen frame encoder, cached beside its shards (issue 25).

Training on 64×64 RGB clips spends most of a CPU step in the convolutions (docs/decisions.md,
"Cost"). With a frame encoder trained once and frozen, every frame's embedding is the same at every
step, so it is computed once: a cache file
``<dataset folder>/embeddings/<split>-<fingerprint[:16]>.h5`` holds

* ``embeddings`` float32 ``(n, L, E)``: the encoder's output (eval mode) for every frame of every clip;
* ``length`` int32 ``(n,)`` and, where the shards have them, ``keyframes`` bool ``(n, L)``, copied;

with the attributes ``encoder`` (the encoder's :func:`encoder_fingerprint`), ``sources`` (JSON: each
shard's file and SHA-256 from the dataset's manifest) and ``n_cond``. A cache whose encoder or
sources differ from the ones asked for is stale: :func:`cached_embeddings` encodes the split again.
The file is written under a temporary name and renamed (:mod:`keyin.io`), so a reader finds a whole
cache or none.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path

import h5py
import numpy as np
import torch
from rich.progress import Progress
from torch import nn
from torch.utils.data import Dataset

from keyin.data.clips import future_labels
from keyin.data.hdf5 import inspect_shard, read_manifest, split_files
from keyin.errors import DatasetFormatError
from keyin.io import remove_stale_temporaries, temporary_path

CACHE_FOLDER = "embeddings"
FINGERPRINT_CHARS = 16  # of the fingerprint in a cache's file name


def encoder_fingerprint(encoder: nn.Module) -> str:
    """SHA-256 of an encoder's class and every tensor of its state (names, dtypes, shapes, bytes).

    Any change of a weight or a normalisation statistic changes it; the same weights give the same
    fingerprint in any process.
    """
    digest = hashlib.sha256(f"{type(encoder).__module__}.{type(encoder).__qualname__}".encode())
    for name, tensor in sorted(encoder.state_dict().items()):
        data = tensor.detach().cpu().contiguous().reshape(-1)
        digest.update(f"{name}:{data.dtype}:{tuple(tensor.shape)}".encode())
        digest.update(data.view(torch.uint8).numpy().tobytes())
    return digest.hexdigest()


def cache_path(folder: Path, split: str, fingerprint: str) -> Path:
    """Where ``split``'s embeddings under the encoder of ``fingerprint`` are cached."""
    return Path(folder) / CACHE_FOLDER / f"{split}-{fingerprint[:FINGERPRINT_CHARS]}.h5"


def split_sources(folder: Path, split: str) -> list[dict[str, str]]:
    """The manifest's ``[{"file", "sha256"}]`` of a split's shards, the identity of the frames encoded."""
    entries = read_manifest(folder)["splits"].get(split) or []
    return [{"file": entry["file"], "sha256": entry["sha256"]} for entry in entries]


def stale_reason(path: Path, fingerprint: str, sources: list[dict[str, str]]) -> str | None:
    """Why the cache at ``path`` cannot be used for this encoder and these shards; None if it can."""
    if not path.is_file():
        return "no cache yet"
    try:
        with h5py.File(path, "r") as handle:
            encoder = handle.attrs.get("encoder")
            cached_sources = json.loads(handle.attrs.get("sources", "null"))
            complete = "embeddings" in handle and "length" in handle
    except (OSError, json.JSONDecodeError) as err:
        return f"unreadable ({err})"
    if encoder != fingerprint:
        return "made by another encoder"
    if cached_sources != sources:
        return "made from other shards (the dataset was regenerated)"
    return None if complete else "incomplete"


@torch.no_grad()
def encode_shards(shards: list[Path], encoder: nn.Module, batch_size: int = 32, progress: bool = True) -> dict[str, np.ndarray]:
    """Every frame of the shards' clips through the encoder, in eval mode.

    Args:
        shards: validated keyin shards of one split, in order.
        encoder: frames (B, L, C, H, W) in [0, 1] -> (B, L, E).
        batch_size: clips per forward pass.
    Returns:
        ``embeddings`` float32 (n, L, E), ``length`` int32 (n,) and, if every shard has them,
        ``keyframes`` bool (n, L), the clips of all shards concatenated in order.
    """
    was_training = encoder.training
    encoder.eval()
    parts: dict[str, list[np.ndarray]] = {"embeddings": [], "length": [], "keyframes": []}
    device = next(encoder.parameters()).device
    total = sum(inspect_shard(path).n for path in shards)
    try:
        with Progress(disable=not progress) as bar:
            task = bar.add_task("encoding frames", total=total)
            for path in shards:
                with h5py.File(path, "r") as handle:
                    for start in range(0, handle["frames"].shape[0], batch_size):
                        frames = torch.from_numpy(handle["frames"][start : start + batch_size])  # (B, L, H, W, C)
                        frames = frames.to(device).permute(0, 1, 4, 2, 3).float().div_(255.0)
                        parts["embeddings"].append(encoder(frames).float().cpu().numpy())
                        bar.update(task, advance=len(frames))
                    parts["length"].append(handle["length"][()].astype(np.int32))
                    if "keyframes" in handle:
                        parts["keyframes"].append(handle["keyframes"][()].astype(bool))
    finally:
        encoder.train(was_training)
    arrays = {name: np.concatenate(values) for name, values in parts.items() if values}
    if len(parts["keyframes"]) != len(shards):
        arrays.pop("keyframes", None)
    return arrays


def write_cache(path: Path, arrays: dict[str, np.ndarray], fingerprint: str, sources: list[dict[str, str]], n_cond: int) -> None:
    """Write a cache file whole under a temporary name, then rename it into place."""
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(path.parent)
    tmp = temporary_path(path)
    try:
        with h5py.File(tmp, "w") as out:
            for name, value in arrays.items():
                out.create_dataset(name, data=value)
            out.attrs["encoder"] = fingerprint
            out.attrs["sources"] = json.dumps(sources)
            out.attrs["n_cond"] = n_cond
        os.replace(tmp, path)
    finally:
        tmp.unlink(missing_ok=True)


def cached_embeddings(
    folder: Path, split: str, encoder: nn.Module, batch_size: int = 32, progress: bool = True
) -> Path:
    """The cache of ``split``'s embeddings under ``encoder``, encoded first if missing or stale.

    Args:
        folder: a dataset folder with its manifest (``<data_dir>/<dataset>``).
        split: e.g. "train".
        encoder: the frozen frame encoder; its fingerprint names and checks the cache.
    Returns:
        the path of a valid cache file.
    """
    folder = Path(folder)
    fingerprint = encoder_fingerprint(encoder)
    sources = split_sources(folder, split)
    path = cache_path(folder, split, fingerprint)
    if stale_reason(path, fingerprint, sources) is None:
        return path
    shards = split_files(folder, split)  # checks every shard against its checksum
    n_cond = inspect_shard(shards[0]).n_cond
    write_cache(path, encode_shards(shards, encoder, batch_size, progress), fingerprint, sources, n_cond)
    return path


class EmbeddedClips(Dataset):
    """Clips as cached frame embeddings, held in memory; items like :class:`keyin.data.clips.ShardClips`'
    with ``embeddings`` (L, E) float32 in place of ``frames``."""

    def __init__(self, path: Path, n_cond: int, n_future: int, fingerprint: str | None = None) -> None:
        path = Path(path)
        try:
            with h5py.File(path, "r") as handle:
                if fingerprint is not None and handle.attrs.get("encoder") != fingerprint:
                    raise DatasetFormatError(
                        f"{path} holds the embeddings of another encoder; build it again with "
                        f"keyin.data.embeddings.cached_embeddings for this encoder"
                    )
                cached_cond = int(handle.attrs["n_cond"])
                self.embeddings = torch.from_numpy(handle["embeddings"][()])  # (n, L, E)
                self.length = handle["length"][()]
                self.keyframes = handle["keyframes"][()] if "keyframes" in handle else None
        except (OSError, KeyError) as err:
            raise DatasetFormatError(
                f"{path} is not a readable embedding cache ({err}); delete it and let "
                f"cached_embeddings encode the split again"
            ) from None
        if cached_cond != n_cond or self.embeddings.shape[1] < n_cond + n_future:
            raise DatasetFormatError(
                f"{path} has n_cond={cached_cond} and clips of {self.embeddings.shape[1]} frames; the config "
                f"asks n_cond={n_cond}, n_future={n_future}"
            )
        self.n_cond, self.n_future = n_cond, n_future

    def __len__(self) -> int:
        return self.embeddings.shape[0]

    def __getitem__(self, index: int) -> dict[str, torch.Tensor]:
        if not 0 <= index < len(self):
            raise IndexError(index)
        keyframes = None if self.keyframes is None else self.keyframes[index]
        return {
            "embeddings": self.embeddings[index, : self.n_cond + self.n_future],
            **future_labels(int(self.length[index]), keyframes, self.n_cond, self.n_future),
        }

