"""The one on-disk format for every dataset (DESIGN §4): HDF5 shards plus a JSON manifest.

A shard holds ``n`` clips of ``L`` frames each:

* ``frames``    uint8 ``(n, L, H, W, C)``, one clip per chunk, gzip-compressed;
* ``length``    int32 ``(n,)``, valid frames per clip (padding repeats the last frame);
* ``keyframes`` bool ``(n, L)``, ground-truth keyframes on the clip's own time axis (optional);
* any further per-clip arrays (first axis ``n``), e.g. ``positions`` or ``actions``.

File attributes: ``format_version``, ``generator``, ``config`` (JSON), ``seed``, ``split``,
``n_cond`` (conditioning frames at the start of each clip) and ``code_version``.
Shards are written to a temporary name and renamed when complete (:mod:`keyin.io`), so a shard
either exists whole or not at all (a temporary file left by a killed writer is removed by the next
run); the manifest records each shard's SHA-256 so corruption is detected on read.
"""

from __future__ import annotations

import hashlib
import io
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import h5py
import numpy as np

from keyin import __version__
from keyin.data.frames import BLANK_FIX, check_zero_one, is_blank
from keyin.errors import DatasetFormatError
from keyin.io import atomic_write_bytes, atomic_write_text, sha256_of
from keyin.paths import inside

FORMAT_VERSION = 1
MANIFEST_NAME = "manifest.json"
REQUIRED_ATTRS = ("format_version", "generator", "config", "seed", "split", "n_cond")
IMPORT_GENERATOR = "keyin-import"  # the ``generator`` of shards that keyin-import wrote from videos
SAMPLE_CLIPS = 8  # clips per shard whose values a reader checks (spread over the file; 1-6 ms a shard)
# How a shard of 0/1 frames is fixed
SHARD_ZERO_ONE_FIX = "write the file again with frames * 255, or import the 0/1 frames with keyin-import binary=true"
# How a shard of frames of another dtype is fixed
SHARD_DTYPE_FIX = (
    "store frames as uint8 0-255 (float frames in [0, 1]: np.round(frames * 255).astype(np.uint8)), or import "
    "them with keyin-import, which converts float frames in [0, 1]"
)


def write_shard(path: Path, arrays: Mapping[str, np.ndarray], attrs: Mapping[str, Any]) -> str:
    """Write one shard atomically and return its SHA-256.

    Args:
        path: destination ``.h5`` file; its folder must exist.
        arrays: at least ``frames`` (n, L, H, W, C) uint8 and ``length`` (n,); every array's first
            axis is n.
        attrs: ``generator``, ``config`` (a dict, stored as JSON), ``seed``, ``split``, ``n_cond``.
    """
    path = Path(path)
    frames = np.asarray(arrays["frames"])
    if frames.dtype != np.uint8 or frames.ndim != 5:
        raise ValueError(f"frames must be uint8 (n, L, H, W, C), got {frames.dtype} {frames.shape}")
    n = frames.shape[0]
    # Built in memory, then written in one go: HDF5 itself never meets a full disk (h5py can crash
    # the process on a failed flush) and the file appears whole or not at all.
    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as out:
        for name, value in arrays.items():
            value = np.asarray(value)
            if value.shape[0] != n:
                raise ValueError(f"array {name!r} has {value.shape[0]} rows, frames has {n}")
            chunks = (1, *value.shape[1:]) if value.ndim > 1 and n > 0 else None
            out.create_dataset(name, data=value, chunks=chunks, compression="gzip" if chunks else None)
        out.attrs["format_version"] = FORMAT_VERSION
        out.attrs["code_version"] = __version__
        for key, value in attrs.items():
            out.attrs[key] = json.dumps(value) if key == "config" else value
    data = buffer.getvalue()
    atomic_write_bytes(path, data)
    return hashlib.sha256(data).hexdigest()


@dataclass(frozen=True)
class ShardInfo:
    """What a reader needs to know about a shard before touching its frames."""

    path: Path
    n: int
    clip_length: int
    image_shape: tuple[int, int, int]
    n_cond: int
    split: str
    generator: str
    config: dict
    seed: int = 0  # the split's base seed: clip i was made from seed + i
    first_index: int | None = None  # the index of the shard's first clip in its split


def inspect_shard(path: Path) -> ShardInfo:
    """Validate a shard's layout and attributes; raise a ``DatasetFormatError`` naming what differs."""
    path = Path(path)
    if not path.is_file():
        raise DatasetFormatError(
            f"dataset file {path} does not exist; generate it with `keyin-generate` or pass an "
            f"existing file"
        )
    try:
        handle = h5py.File(path, "r")
    except OSError as err:
        raise DatasetFormatError(
            f"{path} is not a readable HDF5 file ({err}); it is truncated or corrupt: regenerate it "
            f"with `keyin-generate`"
        ) from None
    with handle:
        missing = [key for key in REQUIRED_ATTRS if key not in handle.attrs]
        if missing:
            raise DatasetFormatError(
                f"{path} lacks the attributes {missing} of the keyin format; write it with "
                f"keyin.data.hdf5.write_shard"
            )
        version = int(handle.attrs["format_version"])
        if version != FORMAT_VERSION:
            raise DatasetFormatError(
                f"{path} has format_version {version}, this keyin reads {FORMAT_VERSION}; "
                f"regenerate the file with this version's `keyin-generate`"
            )
        for name in ("frames", "length"):
            if name not in handle:
                raise DatasetFormatError(f"{path} has no '{name}' dataset; it is not a keyin shard")
        frames = handle["frames"]
        if frames.ndim != 5:
            raise DatasetFormatError(
                f"{path}: 'frames' must be uint8 (n, L, H, W, C), found {frames.dtype} {frames.shape}"
            )
        if frames.dtype != np.uint8:
            raise DatasetFormatError(
                f"{path} holds {frames.dtype} frames{first_clip_range(frames)}, but keyin's HDF5 format stores uint8 "
                f"0-255; {SHARD_DTYPE_FIX}"
            )
        n, clip_length = frames.shape[:2]
        for name, dataset in handle.items():
            if dataset.shape[:1] != (n,):
                raise DatasetFormatError(
                    f"{path}: '{name}' has {dataset.shape[0]} rows but 'frames' has {n}"
                )
        if "keyframes" in handle and handle["keyframes"].shape != (n, clip_length):
            raise DatasetFormatError(
                f"{path}: 'keyframes' has shape {handle['keyframes'].shape}, expected {(n, clip_length)}"
            )
        try:
            config = json.loads(handle.attrs["config"])
        except (TypeError, json.JSONDecodeError):
            raise DatasetFormatError(f"{path}: attribute 'config' is not valid JSON") from None
        n_cond = int(handle.attrs["n_cond"])
        if not 0 < n_cond < clip_length:
            raise DatasetFormatError(f"{path}: n_cond={n_cond} must lie in [1, {clip_length - 1}]")
        return ShardInfo(
            path=path,
            n=int(n),
            clip_length=int(clip_length),
            image_shape=tuple(int(s) for s in frames.shape[2:]),
            n_cond=n_cond,
            split=str(handle.attrs["split"]),
            generator=str(handle.attrs["generator"]),
            config=config,
            seed=int(handle.attrs["seed"]),
            first_index=int(handle.attrs["first_index"]) if "first_index" in handle.attrs else None,
        )


def check_compatible(
    info: ShardInfo, image_shape: tuple[int, int, int], n_cond: int, n_future: int
) -> None:
    """Refuse a shard whose image size, conditioning or clip length differ from the config."""
    problems = []
    if info.image_shape != tuple(image_shape):
        problems.append(f"image (H, W, C) {info.image_shape} != config {tuple(image_shape)}")
    if info.n_cond != n_cond:
        problems.append(f"n_cond {info.n_cond} != config {n_cond}")
    if info.clip_length < n_cond + n_future:
        problems.append(f"clip length {info.clip_length} < n_cond + n_future = {n_cond + n_future}")
    if problems:
        raise DatasetFormatError(f"{info.path} does not match the dataset config: {'; '.join(problems)}; {mismatch_fix(info)}")


def first_clip_range(frames: h5py.Dataset) -> str:
    """`` in [low, high]``, the values of the first clip of numeric frames; empty for others."""
    if not len(frames) or not np.issubdtype(frames.dtype, np.number):
        return ""
    clip = frames[0]
    return f" in [{clip.min():g}, {clip.max():g}]"


def sample_rows(n: int) -> list[int]:
    """Up to :data:`SAMPLE_CLIPS` clip indices spread evenly over ``range(n)``, the first and last included."""
    return sorted({round(float(i)) for i in np.linspace(0, n - 1, min(n, SAMPLE_CLIPS))})


def check_frame_values(infos: Sequence[ShardInfo]) -> None:
    """Refuse shards of 0/1 frames, or files of blank clips only, by :mod:`keyin.data.frames`' rules.

    Only each shard's :func:`sample_rows` are read, so a 100 000-clip split costs milliseconds per
    shard. A blank clip, even a shard of them, is data (an imported video's black stretch can fill a
    shard); files whose every checked clip is blank are a failed conversion, e.g. float frames cast to
    uint8, and are refused together.
    """
    checked, blank = 0, []
    for info in infos:
        clips = sample_clips(info)
        check_zero_one(clips.dtype, int(clips.max(initial=0)), f"{info.path} ({len(clips)} of {info.n} clips checked)",
                       SHARD_ZERO_ONE_FIX)
        checked += len(clips)
        blank += [clip.flat[0] for clip in clips if is_blank(clip)]
    if checked and len(blank) == checked:
        files = str(infos[0].path) if len(infos) == 1 else f"{infos[0].path} and {len(infos) - 1} more"
        raise DatasetFormatError(
            f"{files}: all {checked} clips checked (of {sum(info.n for info in infos)}) are blank, each one value "
            f"throughout (e.g. {blank[0]}); {BLANK_FIX} and write the file again"
        )


def sample_clips(info: ShardInfo) -> np.ndarray:
    """The frames (k, L, H, W, C) of a shard's :func:`sample_rows`."""
    with h5py.File(info.path, "r") as handle:
        frames = handle["frames"]  # one read per clip: h5py's list indexing is over 10x slower
        return np.stack([frames[row] for row in sample_rows(info.n)]) if info.n else frames[:0]


def mismatch_fix(info: ShardInfo) -> str:
    """What to do about a shard of other sizes: an imported one names the sizes it was imported with."""
    if info.generator != IMPORT_GENERATOR:
        return "pick the matching dataset= option or regenerate the file"
    sizes = " ".join(f"dataset.{key}={info.config[key]}" for key in ("image_size", "channels", "n_cond", "n_future"))
    return f"pass the sizes it was imported with ({sizes}) or import it again with keyin-import"


def load_arrays(path: Path, names: tuple[str, ...] | None = None) -> dict[str, np.ndarray]:
    """Read whole arrays of a validated shard into memory (small files: test sets, tasks)."""
    inspect_shard(path)
    with h5py.File(path, "r") as handle:
        return {name: handle[name][()] for name in (names or tuple(handle.keys()))}


# ---------------------------------------------------------------------------------------------
# Manifest: one JSON per dataset folder listing its shards and their checksums.


def write_manifest(
    folder: Path,
    dataset: str,
    shards: Mapping[str, list[dict]],
    config: Mapping[str, Any],
    sources: list[dict] | None = None,
) -> Path:
    """Atomically write ``folder/manifest.json``.

    Args:
        shards: split name -> list of ``{"file": name, "n": clips, "sha256": hex}``.
        config: the generator (or import) config the shards were made with.
        sources: imported datasets only: one entry per source video, which the shards' ``video``
            array indexes (``keyin.data.imports``).
    """
    manifest = {
        "format_version": FORMAT_VERSION,
        "dataset": dataset,
        "config": dict(config),
        "splits": dict(shards),
    }
    if sources is not None:
        manifest["sources"] = list(sources)
    path = Path(folder) / MANIFEST_NAME
    atomic_write_text(path, json.dumps(manifest, indent=1, sort_keys=True))
    return path


def read_manifest(folder: Path) -> dict:
    """Read and check a dataset folder's manifest."""
    path = Path(folder) / MANIFEST_NAME
    if not path.is_file():
        raise DatasetFormatError(
            f"no {MANIFEST_NAME} in {folder}; generate the dataset with `keyin-generate` "
            f"(or set data_dir= to the folder that holds it)"
        )
    try:
        manifest = json.loads(path.read_text())
    except json.JSONDecodeError as err:
        raise DatasetFormatError(f"{path} is not valid JSON ({err}); regenerate the dataset") from None
    if manifest.get("format_version") != FORMAT_VERSION:
        raise DatasetFormatError(
            f"{path} has format_version {manifest.get('format_version')}, this keyin reads "
            f"{FORMAT_VERSION}; regenerate the dataset"
        )
    return manifest


def split_files(folder: Path, split: str, verify: bool = True) -> list[Path]:
    """The shards of one split, in order, optionally verified against their checksums."""
    folder = Path(folder)
    manifest = read_manifest(folder)
    entries = manifest["splits"].get(split)
    if not entries:
        raise DatasetFormatError(
            f"{folder} has no '{split}' split (it has {sorted(manifest['splits'])}); generate it "
            f"with `keyin-generate`"
        )
    paths = []
    for entry in entries:
        path = inside(folder, entry["file"], str(folder / MANIFEST_NAME))
        if not path.is_file():
            raise DatasetFormatError(
                f"shard {path} listed in the manifest is missing; re-run `keyin-generate` to "
                f"rebuild it"
            )
        if verify and sha256_of(path) != entry["sha256"]:
            raise DatasetFormatError(
                f"shard {path} does not match its checksum in the manifest (corrupt or modified); "
                f"delete it and re-run `keyin-generate` to rebuild it"
            )
        paths.append(path)
    return paths
