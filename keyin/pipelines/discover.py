"""Keyframes of whole videos (keyin-discover): each video's overlapping windows through a discoverer,
merged in the original video's time (:mod:`keyin.decode.merge`), and per video a folder of files
that show them, which appears whole or not at all.

A video's folder holds ``keyframes.json`` (below), ``contact_sheet.png`` (the keyframes),
``timeline.png`` (the segments between them over the video, and the labelled ones beside them when
there are labels) and ``annotated.gif`` (every kept frame, keyframes bordered red, labels green).
The pictures show the frames as the model saw them: centre-cropped, resized, at the frame stride.
"""

from __future__ import annotations

import json
import re
import shutil
import time
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping, Sequence

import torch
from rich.progress import Progress
from torch import Tensor

from keyin.data.clips import clip_item
from keyin.data.imports import ImportedVideo
from keyin.data.windows import cut_window, original_frame, original_time
from keyin.decode.merge import WindowKeyframes, merge_windows
from keyin.decode.segment_costs import window_costs
from keyin.io import atomic_write_text, remove_stale_temporaries, replace_folder, temporary_path

Discoverer = Callable[..., list[list[int]]]  # (B, L, C, H, W), (B,)[, costs=(B, N, S)] -> per clip, future positions
VideoCosts = Callable[[Tensor, Tensor | None], Tensor | None]  # (T, H, W, C) uint8, (T - 1, S) kept -> (T - 1, S) costs, or None
Segments = Callable[[Tensor, Tensor], Tensor]  # (B, L, C, H, W), (B,) -> (B, N, S) the segments a window prices
Scorer = Callable[[Tensor, Tensor], Tensor]  # (B, L, C, H, W), (B,) -> (B, N) a score per future position
FILES = ("keyframes.json", "contact_sheet.png", "timeline.png", "annotated.gif")
SCORE = ("the probability of a keyframe at this frame under the model's posterior offsets, read along "
         "their argmax chain (keyin.decode.rules.keyin_keyframe_probabilities)")


@dataclass(frozen=True)
class Keyframe:
    """A keyframe of a video, in the original video's time."""

    frame: int  # the original video's frame, from 0
    time: float | None  # seconds from the video's start; None where its frame rate is unknown
    score: float
    window: int  # the window that owns it (keyin.decode.merge)


def window_batches(
    video: ImportedVideo, n_cond: int, n_future: int, batch_size: int
) -> Iterator[tuple[list[int], Tensor, Tensor]]:
    """A video's windows as model input: per batch the windows' first kept frames, (B, L, C, H, W)
    clips in [0, 1] (padded by repeating the last frame) and (B,) valid future frames."""
    for first in range(0, len(video.starts), batch_size):
        starts = video.starts[first : first + batch_size]
        cut = (cut_window(video.frames, start, n_cond + n_future) for start in starts)
        items = [clip_item({"frames": window, "length": length}, n_cond, n_future) for window, length in cut]
        yield starts, torch.stack([i["frames"] for i in items]), torch.stack([i["future_length"] for i in items])


def video_segments(video: ImportedVideo, segments: Segments, n_cond: int, n_future: int, batch_size: int) -> Tensor:
    """(T - 1, S) bool on the video's kept frames: the segments that any of its windows prices
    (``segments`` per window; row ``t`` starts at kept frame ``t``, as in :func:`window_costs`)."""
    if not len(video.starts):
        raise ValueError(f"video {video.id!r} has no windows, so no segments to price")
    counts = None
    for starts, clips, future_length in window_batches(video, n_cond, n_future, batch_size):
        keep = segments(clips, future_length).cpu()  # (B, N, S)
        if counts is None:
            counts = torch.zeros(len(video.frames) - 1, keep.shape[2], dtype=torch.long)
        firsts = torch.tensor(starts) + n_cond - 1  # each window's extended index 0 on the video
        rows = (firsts[:, None] + torch.arange(n_future)).clamp(max=len(counts) - 1)  # padded rows keep nothing
        counts.index_put_((rows.flatten(),), keep.flatten(0, 1).long(), accumulate=True)
    return counts > 0


@torch.no_grad()
def discover_video(
    video: ImportedVideo,
    discoverer: Discoverer,
    scorer: Scorer,
    n_cond: int,
    n_future: int,
    frame_stride: int,
    seam: int = 1,
    batch_size: int = 32,
    advance: Callable[[int], Any] = lambda windows: None,
    video_costs: VideoCosts | None = None,
    segments: Segments | None = None,
) -> list[Keyframe]:
    """The keyframes of one video: every window's, merged (:func:`keyin.decode.merge.merge_windows`),
    mapped to the original video's frames (:func:`keyin.data.windows.original_frame`) and seconds.

    Args:
        video: its kept frames (T', H, W, C) uint8 and its windows' starts.
        discoverer: future positions per clip, inside each clip's valid frames.
        scorer: (B, N) a score per future position; a keyframe's score is its position's.
        advance: called with the number of windows done after each batch (a progress bar).
        video_costs: the segment costs of the whole video, computed once for the overlapping windows
            and passed to ``discoverer`` as each window's ``costs``; None (or it returns None): none.
        segments: with ``video_costs``, the segments each window prices (a pruned rule): the video's
            costs are computed for their union only; None: every segment.
    """
    keep = None if video_costs is None or segments is None else video_segments(video, segments, n_cond, n_future, batch_size)
    shared = None if video_costs is None else video_costs(torch.from_numpy(video.frames), keep)
    windows = []
    for starts, clips, future_length in window_batches(video, n_cond, n_future, batch_size):
        if shared is None:
            positions = discoverer(clips, future_length)
        else:  # a window's extended index 0 (K^0) is its last conditioning frame
            firsts = torch.tensor(starts) + n_cond - 1
            positions = discoverer(clips, future_length, costs=window_costs(shared, firsts, future_length, n_future))
        scores = scorer(clips, future_length)
        for start, length, row, row_scores in zip(starts, future_length.tolist(), positions, scores, strict=True):
            windows.append(WindowKeyframes(start, n_cond + length, list(row), [float(row_scores[p]) for p in row]))
        advance(len(starts))
    keyframes = []
    for merged in merge_windows(windows, n_cond, seam):
        start = windows[merged.window].start
        frame = original_frame(start * frame_stride, frame_stride, n_cond + merged.position)
        seconds = original_time(frame, video.fps)
        seconds = None if seconds is None else round(seconds, 6)
        keyframes.append(Keyframe(frame, seconds, round(merged.score, 4), merged.window))
    return keyframes


def folder_names(ids: Sequence[str]) -> list[str]:
    """A folder name per video id: its letters, digits and ``.-_`` (others become ``_``), made unique
    by a ``-2``, ``-3``, … suffix."""
    names, seen = [], set()
    for video_id in ids:
        base = re.sub(r"[^A-Za-z0-9._-]+", "_", video_id).strip("._") or "video"
        name, count = base, 1
        while name in seen:
            count += 1
            name = f"{base}-{count}"
        seen.add(name)
        names.append(name)
    return names


def keyframes_record(
    video: ImportedVideo, keyframes: Sequence[Keyframe], model: Mapping[str, Any], n_cond: int, frame_stride: int,
    window_stride: int,
) -> dict[str, Any]:
    """What ``keyframes.json`` holds (docs/discover.md): the video, the model and rule, the windows,
    and the keyframes in the original video's frames and seconds with their scores."""
    return {
        "video": video.id,
        "path": str(video.path.resolve()),
        "frames": video.n_frames,
        "fps": video.fps,
        "camera": video.camera,
        "stored_size": list(video.stored_shape),
        "frame_stride": frame_stride,
        "first_candidate": n_cond * frame_stride,
        "windows": {"count": len(video.starts), "stride": window_stride * frame_stride,
                    "starts": [start * frame_stride for start in video.starts]},
        "model": dict(model),
        "score": SCORE,
        "keyframes": [asdict(keyframe) for keyframe in keyframes],
        "labels": video.labels,
    }


def caption(keyframe: Keyframe) -> str:
    seconds = "" if keyframe.time is None else f" · {keyframe.time:.2f} s"
    return f"frame {keyframe.frame}{seconds}\nscore {keyframe.score:.2f}"


def write_video_folder(
    folder: Path, video: ImportedVideo, keyframes: Sequence[Keyframe], record: Mapping[str, Any], n_cond: int,
    frame_stride: int, pictures: bool = True,
) -> Path:
    """Write the video's files (:data:`FILES`; only keyframes.json without ``pictures``) into a
    temporary folder beside ``folder`` and rename it into place, so a crash leaves no half-written folder."""
    staging = temporary_path(folder)
    try:
        staging.mkdir(parents=True)
        atomic_write_text(staging / "keyframes.json", json.dumps(dict(record), indent=1))
        if pictures:
            save_pictures(staging, video, keyframes, n_cond, frame_stride)
        replace_folder(staging, folder)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return folder


def save_pictures(folder: Path, video: ImportedVideo, keyframes: Sequence[Keyframe], n_cond: int, frame_stride: int) -> None:
    """One video's contact sheet, timeline and annotated GIF into ``folder`` (at a cheap rule, most of
    keyin-discover's time: benchmarks/results/discover_speed.md)."""
    from keyin.viz.discovered import save_annotated_gif, save_contact_sheet, save_timeline  # matplotlib: only for pictures

    kept = [keyframe.frame // frame_stride for keyframe in keyframes]
    save_contact_sheet(folder / "contact_sheet.png", video.frames[kept], [caption(k) for k in keyframes], video.id)
    save_timeline(
        folder / "timeline.png", video.n_frames, [k.frame for k in keyframes], [k.score for k in keyframes],
        n_cond * frame_stride, video.fps, video.labels, video.id,
    )
    labels = None if video.labels is None else video.keyframes(frame_stride)
    duration = 1000 * frame_stride / video.fps if video.fps else 100
    save_annotated_gif(folder / "annotated.gif", video.frames, n_cond, kept, labels, duration)


def discover_videos(
    videos: Sequence[ImportedVideo],
    discoverer: Discoverer,
    scorer: Scorer,
    folder: Path,
    model: Mapping[str, Any],
    n_cond: int,
    n_future: int,
    frame_stride: int,
    window_stride: int,
    seam: int = 1,
    batch_size: int = 32,
    progress: bool = True,
    pictures: bool = True,
    video_costs: VideoCosts | None = None,
    segments: Segments | None = None,
) -> dict[str, Any]:
    """Discover every video's keyframes and write its folder ``<folder>/<video name>/`` (keyframes.json,
    and with ``pictures`` the contact sheet, timeline and annotated GIF).

    Args:
        model: what ``keyframes.json`` says about the model (checkpoint, method, rule, sizes).
        window_stride: kept frames between window starts (recorded; the starts are the videos').
        video_costs, segments: see :func:`discover_video`.
    Returns:
        A summary: videos, each one's folder and keyframe count, kept frames and windows run,
        seconds and kept frames per second.
    """
    started, folder = time.perf_counter(), Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(folder)
    found = {}
    with Progress(disable=not progress) as bar:
        task = bar.add_task("discovering keyframes", total=sum(len(video.starts) for video in videos))
        for video, name in zip(videos, folder_names([video.id for video in videos]), strict=True):
            keyframes = discover_video(
                video, discoverer, scorer, n_cond, n_future, frame_stride, seam, batch_size,
                advance=lambda windows: bar.update(task, advance=windows), video_costs=video_costs, segments=segments,
            )
            record = keyframes_record(video, keyframes, model, n_cond, frame_stride, window_stride)
            write_video_folder(folder / name, video, keyframes, record, n_cond, frame_stride, pictures)
            found[video.id] = {"folder": name, "keyframes": len(keyframes)}
    seconds = time.perf_counter() - started
    kept = sum(len(video.frames) for video in videos)
    return {
        "videos": found,
        "kept_frames": kept,
        "windows": sum(len(video.starts) for video in videos),
        "seconds": round(seconds, 2),
        "kept_frames_per_second": round(kept / seconds, 1) if seconds else None,
    }
