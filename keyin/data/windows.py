"""Index arithmetic of imported videos, pure: the windows cut from a video, their padding and
keyframes, the split by video, and the way back from a clip position to the original frame.

An original video has frames 0 … T-1. With frame stride k it keeps the originals 0, k, 2k, …
(kept frame j is original j·k). A window is a clip of L = n_cond + n_future kept frames from kept
frame s on, so clip position p shows the original frame (s + p)·k; a window shorter than L (the
video's end) is padded by repeating its last frame, with ``length`` its valid frames, as every
keyin clip is.
"""

from __future__ import annotations

from typing import Iterable, Mapping

import numpy as np

from keyin.errors import DatasetFormatError


def window_starts(n_kept: int, clip_length: int, n_cond: int, window_stride: int, min_future: int) -> list[int]:
    """The first kept frames of a video's windows: every ``window_stride``-th frame until a window
    reaches the video's end, each window holding at least ``n_cond + min_future`` frames (none if
    the video is shorter than that). With ``window_stride = n_future`` every frame after the first
    ``n_cond`` is a future frame of exactly one window."""
    starts, start = [], 0
    while n_kept - start >= n_cond + min_future:
        starts.append(start)
        if start + clip_length >= n_kept:
            break
        start += window_stride
    return starts


def cut_window(frames: np.ndarray, start: int, clip_length: int) -> tuple[np.ndarray, int]:
    """Frames ``start`` … ``start + clip_length - 1`` of (T, ...) ``frames``, the missing ones at the
    end repeating the last; returns the (clip_length, ...) window and its valid frames."""
    window = frames[start : start + clip_length]
    length = len(window)
    padding = np.repeat(window[-1:], clip_length - length, axis=0)
    return np.concatenate([window, padding]), length


def kept_keyframes(label_frames: Iterable[int], frame_stride: int, n_kept: int) -> list[int]:
    """Original keyframe numbers → kept-frame indices: each to its nearest kept frame (a tie to the
    earlier one), sorted, without repeats."""
    nearest = ((frame + (frame_stride - 1) // 2) // frame_stride for frame in label_frames)
    return sorted({min(index, n_kept - 1) for index in nearest})


def window_keyframes(keyframes: Iterable[int], start: int, clip_length: int) -> np.ndarray:
    """(clip_length,) bool: the kept-frame keyframes that fall in the window from ``start`` on."""
    marks = np.zeros(clip_length, dtype=bool)
    for index in keyframes:
        if start <= index < start + clip_length:
            marks[index - start] = True
    return marks


def split_videos(n_videos: int, fractions: Mapping[str, float], seed: int) -> dict[str, list[int]]:
    """Videos 0 … n_videos-1 drawn into splits of the given fractions (summing to 1), by a
    permutation seeded with ``seed``: each split with a positive fraction gets at least one video,
    the counts are the fractions of n_videos rounded by largest remainder. Each split's videos are
    in index order.

    Raises:
        DatasetFormatError: fewer videos than splits with a positive fraction.
    """
    names = [name for name, fraction in fractions.items() if fraction > 0]
    if n_videos < len(names):
        raise DatasetFormatError(
            f"{n_videos} video(s) cannot be split by video into {len(names)} splits ({', '.join(names)}); "
            f"import more videos or give fewer splits a fraction (e.g. fractions='{{train: 1.0, val: 0, test: 0}}')"
        )
    exact = {name: fractions[name] * n_videos for name in names}
    counts = {name: max(1, int(exact[name])) for name in names}
    while sum(counts.values()) < n_videos:  # the largest remainder first
        counts[max(names, key=lambda name: exact[name] - counts[name])] += 1
    while sum(counts.values()) > n_videos:  # a minimum of one took from the most over-served
        counts[max((n for n in names if counts[n] > 1), key=lambda name: counts[name] - exact[name])] -= 1
    order = np.random.default_rng(seed).permutation(n_videos)
    splits, first = {}, 0
    for name in names:
        splits[name] = sorted(int(video) for video in order[first : first + counts[name]])
        first += counts[name]
    return splits


def original_frame(first_frame: int, frame_stride: int, position: int) -> int:
    """The original video's frame at clip position ``position`` of a window whose position 0 is the
    original ``first_frame`` (a discoverer's future position p is clip position n_cond + p)."""
    return first_frame + position * frame_stride


def original_time(frame: int, fps: float | None) -> float | None:
    """Seconds from the video's start to its frame ``frame`` (None if its frame rate is unknown)."""
    return None if fps is None or not np.isfinite(fps) else frame / fps
