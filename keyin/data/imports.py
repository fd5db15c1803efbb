"""Import a source's videos as a keyin dataset folder: HDF5 shards and a manifest, in one go.

Every video is decoded, checked and fitted (:mod:`keyin.data.frames`) before anything is written,
so bad input stops the import with the destination untouched. The shards and the manifest are then
written into a temporary folder beside the destination, which takes the destination's place by a
rename once complete (:func:`keyin.io.replace_folder`): a reader finds the old dataset or the new
one, never a mix, and a killed import leaves only its temporary folder, removed by the next one.

Besides the format's ``frames``, ``length`` and (with labels) ``keyframes``, each clip keeps where
it came from, so a keyframe maps back to the original video (:func:`clip_origins`):

* ``video`` int32 (n,): the index of its video in the manifest's ``sources`` (id, path, frames, fps, camera);
* ``first_frame`` int32 (n,): the original frame at clip position 0;
* ``frame_stride`` int32 (n,): original frames from one clip position to the next;
* ``fps`` float32 (n,): the video's frame rate, NaN if unknown.
"""

from __future__ import annotations

import shutil
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from rich.progress import Progress

from keyin.data.frames import BLANK_FIX, is_blank, prepare_video
from keyin.data.generate import plan_shards
from keyin.data.hdf5 import IMPORT_GENERATOR, load_arrays, read_manifest, split_files, write_manifest, write_shard
from keyin.data.labels import check_known, check_video_labels, read_labels
from keyin.data.sources import find_videos
from keyin.data.windows import (
    cut_window,
    kept_keyframes,
    original_frame,
    original_time,
    split_videos,
    window_keyframes,
    window_starts,
)
from keyin.errors import DatasetFormatError
from keyin.io import remove_stale_temporaries, replace_folder, temporary_path

ORIGIN_ARRAYS = ("video", "first_frame", "frame_stride", "fps")


@dataclass(frozen=True)
class ImportSpec:
    """How videos become clips: the model's sizes and the import's choices."""

    image_size: int
    channels: int
    n_cond: int
    n_future: int
    frame_stride: int = 1  # keep every k-th original frame
    window_stride: int = 0  # kept frames from one window's start to the next; 0: n_future
    min_future: int = 1  # a window needs this many future frames (a shorter video is skipped)
    binary: bool = False  # integer frames stored as 0/1 are scaled to 0/255
    fps: float | None = None  # the frame rate of sources that store none (frames, arrays, robomimic)
    camera_key: str | None = None  # robomimic (None: agentview_image) or LeRobot (None: its only camera)

    @property
    def clip_length(self) -> int:
        return self.n_cond + self.n_future

    @property
    def stride(self) -> int:
        return self.window_stride or self.n_future


@dataclass
class ImportedVideo:
    """One video, fitted: (T', H, W, C) uint8 kept frames, its labels and its windows."""

    id: str
    path: Path
    n_frames: int  # original frames
    fps: float | None
    frames: np.ndarray
    labels: list[int] | None  # keyframes as original frame numbers; None: the import has no labels
    starts: list[int]  # its windows' first kept frames
    stored_shape: tuple[int, int, int]  # (H, W, C) of its frames as stored, before fitting
    where: str  # how messages name it (:attr:`keyin.data.sources.Video.where`)
    camera: str | None = None  # the camera read (robomimic, LeRobot), None for a video of its own

    def keyframes(self, frame_stride: int) -> list[int]:
        """The labels as kept-frame indices."""
        return kept_keyframes(self.labels or [], frame_stride, len(self.frames))


@dataclass(frozen=True)
class Origin:
    """Where a clip came from; ``frame(p)`` and ``time(p)`` give the original frame and second of
    clip position p (a discoverer's future position p is clip position n_cond + p)."""

    video: str
    path: str
    first_frame: int
    frame_stride: int
    fps: float | None

    def frame(self, position: int) -> int:
        return original_frame(self.first_frame, self.frame_stride, position)

    def time(self, position: int) -> float | None:
        return original_time(self.frame(position), self.fps)


def import_videos(
    source: Path,
    folder: Path,
    dataset: str,
    spec: ImportSpec,
    fractions: Mapping[str, float],
    seed: int,
    shard_size: int,
    labels: Path | None = None,
    overwrite: bool = False,
    progress: bool = True,
) -> dict[str, Any]:
    """Import ``source`` into ``folder`` (see the module docstring).

    Args:
        fractions: split name -> share of the videos (summing to 1); the split is by video.
        seed: the split's seed.
        labels: a labels file (:mod:`keyin.data.labels`), or None for clips without keyframes.
    Returns:
        Statistics: videos imported and skipped (too short), clips per split, shards, original frames
        read, seconds, and the warnings for the user (why each skipped video was, unlabelled videos).
    Raises:
        DatasetFormatError: bad input (named with its fix); nothing is written then.
    """
    folder, started = Path(folder), time.perf_counter()
    if folder.exists() and not overwrite:
        raise DatasetFormatError(
            f"{folder} already exists; pass overwrite=true to replace it, or import under another "
            f"dataset.name= or data_dir="
        )
    label_map = read_labels(labels) if labels is not None else None
    videos, skipped, seen = read_videos(source, spec, label_map, labels, progress)
    if label_map is not None:
        check_known(label_map, labels, seen)
    if not videos:
        raise DatasetFormatError(
            f"no video of {source} is long enough for one clip ({skipped[0]}); lower dataset.n_cond, frame_stride "
            f"or min_future, or import longer videos"
        )
    splits = split_videos(len(videos), fractions, seed)
    config = dict(asdict(spec), source=str(Path(source).resolve()), labels=str(labels) if labels else None,
                  fractions=dict(fractions), seed=seed)
    folder.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(folder.parent)  # a killed import's folder
    staging = temporary_path(folder)
    try:
        staging.mkdir()
        entries = write_splits(staging, videos, splits, spec, config, seed, shard_size)
        write_manifest(staging, dataset, entries, config, sources(videos, splits))
        replace_folder(staging, folder)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    warnings = [f"{reason}: skipped" for reason in skipped]
    if label_map is not None:
        unlabelled = [video.id for video in videos if video.id not in label_map]
        if unlabelled:
            warnings.append(f"{len(unlabelled)} video(s) have no labels in {labels} (e.g. {unlabelled[0]}): "
                            f"their clips have no keyframes, which F1 counts as truth")
    return {
        "videos": len(videos),
        "skipped": len(skipped),
        "clips": {split: sum(e["n"] for e in shard_list) for split, shard_list in entries.items()},
        "shards": sum(len(shard_list) for shard_list in entries.values()),
        "frames_read": sum(video.n_frames for video in videos),
        "seconds": round(time.perf_counter() - started, 2),
        "warnings": warnings,
    }


def read_videos(
    source: Path,
    spec: ImportSpec,
    labels: dict | None,
    labels_path: Path | None,
    progress: bool,
    verb: str = "importing",
    key: str = "source",
) -> tuple[list[ImportedVideo], list[str], list[str]]:
    """Decode, check and fit every video of ``source``; returns those long enough for a clip, why each
    other one was skipped, and every video id seen (``verb`` names the work in the progress bar,
    ``key`` the setting that named the source in the errors). A source of blank videos only is refused."""
    videos, skipped, seen = [], [], []
    with Progress(disable=not progress) as bar:
        task = bar.add_task(f"{verb} {source}", total=None)
        for video in find_videos(source, spec.camera_key, key):
            seen.append(video.id)
            frames, n_frames, stored_shape = prepare_video(
                video.frames, video.where, spec.image_size, spec.channels, spec.frame_stride, spec.binary
            )
            labelled = None
            if labels is not None:
                labelled = check_video_labels(labels, labels_path, video.id, video.where, n_frames)
            starts = window_starts(len(frames), spec.clip_length, spec.n_cond, spec.stride, spec.min_future)
            if starts:
                fps = video.fps or spec.fps
                videos.append(
                    ImportedVideo(video.id, video.path, n_frames, fps, frames, labelled, starts, stored_shape, video.where,
                                  video.camera)
                )
            else:
                skipped.append(
                    f"{video.where} has {len(frames)} frame(s) at frame_stride={spec.frame_stride}, fewer than "
                    f"dataset.n_cond + min_future = {spec.n_cond + spec.min_future}"
                )
            bar.update(task, advance=1)
    check_not_all_blank(videos, source)
    return videos, skipped, seen


def check_not_all_blank(videos: list[ImportedVideo], source: Path) -> None:
    """Refuse a source whose every video is blank (one value throughout). One blank video among others
    is kept: a black or covered-camera recording is data; a source of nothing but blank videos is a
    failed conversion (or the wrong camera) and would give a model nothing to find."""
    if videos and all(is_blank(video.frames) for video in videos):
        first = videos[0]
        raise DatasetFormatError(
            f"every video of {source} is blank (e.g. {first.where} is {first.frames.flat[0]} throughout); {BLANK_FIX}, "
            f"or pass videos that show something"
        )


def write_splits(
    folder: Path,
    videos: list[ImportedVideo],
    splits: Mapping[str, list[int]],
    spec: ImportSpec,
    config: Mapping[str, Any],
    seed: int,
    shard_size: int,
) -> dict[str, list[dict]]:
    """Write every split's windows as shards of at most ``shard_size`` clips; returns the manifest's
    entries per split."""
    windows = {split: [(v, start) for v in members for start in videos[v].starts] for split, members in splits.items()}
    entries: dict[str, list[dict]] = {split: [] for split in splits}
    for job in plan_shards({split: len(rows) for split, rows in windows.items()}, shard_size):
        rows = windows[job.split][job.start : job.start + job.count]
        arrays = window_arrays([(videos[v], v, start) for v, start in rows], spec)
        attrs = dict(generator=IMPORT_GENERATOR, config=dict(config), seed=seed, split=job.split, n_cond=spec.n_cond,
                     first_index=job.start)
        checksum = write_shard(folder / job.file, arrays, attrs)
        entries[job.split].append({"file": job.file, "n": job.count, "sha256": checksum})
    return entries


def window_arrays(rows: list[tuple[ImportedVideo, int, int]], spec: ImportSpec) -> dict[str, np.ndarray]:
    """The shard arrays of (video, its index, window start) rows (see the module docstring)."""
    cut = [cut_window(video.frames, start, spec.clip_length) for video, _, start in rows]
    arrays = {
        "frames": np.stack([frames for frames, _ in cut]),
        "length": np.array([length for _, length in cut], dtype=np.int32),
        "video": np.array([index for _, index, _ in rows], dtype=np.int32),
        "first_frame": np.array([start * spec.frame_stride for _, _, start in rows], dtype=np.int32),
        "frame_stride": np.full(len(rows), spec.frame_stride, dtype=np.int32),
        "fps": np.array([np.nan if video.fps is None else video.fps for video, _, _ in rows], dtype=np.float32),
    }
    if rows[0][0].labels is not None:
        arrays["keyframes"] = np.stack(
            [window_keyframes(video.keyframes(spec.frame_stride), start, spec.clip_length) for video, _, start in rows]
        )
    return arrays


def sources(videos: list[ImportedVideo], splits: Mapping[str, list[int]]) -> list[dict]:
    """The manifest's ``sources``: per imported video its id, path, split, frames, fps, camera, clips, labels."""
    split_of = {index: split for split, members in splits.items() for index in members}
    return [
        {"id": video.id, "path": str(video.path.resolve()), "split": split_of[index], "frames": video.n_frames,
         "fps": video.fps, "camera": video.camera, "clips": len(video.starts), "labels": video.labels}
        for index, video in enumerate(videos)
    ]


def clip_origins(folder: Path, split: str) -> list[Origin]:
    """Where each clip of an imported split came from, in the order ``ShardClips`` reads them."""
    manifest = read_manifest(folder)
    if "sources" not in manifest:
        raise DatasetFormatError(f"{folder} was not made by keyin-import (its manifest has no sources)")
    origins = []
    for path in split_files(folder, split):
        arrays = load_arrays(path, ORIGIN_ARRAYS)
        for video, first, stride, fps in zip(*(arrays[name].tolist() for name in ORIGIN_ARRAYS)):
            entry = manifest["sources"][video]
            origins.append(Origin(entry["id"], entry["path"], first, stride, None if np.isnan(fps) else fps))
    return origins
