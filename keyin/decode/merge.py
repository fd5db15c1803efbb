"""Keyframes of a whole video from its overlapping windows, merged into one list (pure).

A video of T kept frames (after the frame stride) is cut into windows of L = n_cond + N kept frames
every ``window_stride`` frames (:func:`keyin.data.windows.window_starts`); the window from kept
frame s with ``length`` valid frames shows kept frames s … s + length - 1, and a discoverer marks
future positions p in it, kept frame s + n_cond + p. The merge rule:

1. **Candidates.** A window's candidates are its valid future frames but its last one. Its first
   n_cond frames only condition the model, so the first n_cond kept frames of a video are never
   keyframes. A segmentation closes every window at its last valid frame, which is the window's
   end, no event; a rule that marks a sequence's end in a short last window
   (:func:`keyin.decode.rules.with_sequence_ends`) would otherwise mark a video's last frame or not
   depending on where its windows happen to end.
2. **Ownership.** Every candidate frame belongs to the one window in which it is most central:
   of the windows whose candidate span ``[a, b]`` holds frame f, the one with the largest
   ``min(f - a, b - f)``, farthest from that window's edges where the model sees the least of the
   motion around f; ties go to the earlier window. A window keeps only the keyframes on frames it
   owns, so every frame is decided by exactly one window. With ``window_stride <= N - 1`` the spans
   of neighbouring windows meet, and every frame but the first n_cond and the video's last has an
   owner; a stride of N leaves each window's last frame to no one.
3. **Seams.** Where the frames of two windows meet, both may mark one event a frame apart, each on
   its own side. Kept keyframes of different windows at most ``seam`` kept frames apart are one
   keyframe: the higher score stays (a tie: the earlier frame). ``seam=0`` keeps them all.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np


@dataclass(frozen=True)
class WindowKeyframes:
    """What a discoverer found in one window.

    Attributes:
        start: the window's first kept frame.
        length: its valid frames, conditioning frames included (L for a full window).
        positions: the future positions it marked.
        scores: one score per position.
    """

    start: int
    length: int
    positions: Sequence[int]
    scores: Sequence[float]


@dataclass(frozen=True)
class MergedKeyframe:
    """A keyframe of the whole video: its kept frame, score, and the window and position it came from."""

    kept: int
    score: float
    window: int
    position: int


def candidate_span(window: WindowKeyframes, n_cond: int) -> tuple[int, int]:
    """The first and last kept frame that ``window`` may mark (rule 1); last < first if none."""
    return window.start + n_cond, window.start + window.length - 2


def window_owners(windows: Sequence[WindowKeyframes], n_cond: int) -> np.ndarray:
    """(T,) int: the index of the window that owns each kept frame (rule 2), -1 where none may mark
    it (the first n_cond frames, a window's last valid frame at the video's end); T is the last
    valid frame of any window + 1."""
    n_kept = max((w.start + w.length for w in windows), default=0)
    owners = np.full(n_kept, -1, dtype=np.int64)
    best = np.full(n_kept, -1, dtype=np.int64)  # the owner's min distance to its span's edges
    for index, window in enumerate(windows):
        first, last = candidate_span(window, n_cond)
        if last < first:
            continue
        frames = np.arange(first, last + 1)
        central = np.minimum(frames - first, last - frames)
        wins = central > best[frames]  # strictly: a tie stays with the earlier window
        owners[frames[wins]], best[frames[wins]] = index, central[wins]
    return owners


def merge_windows(windows: Sequence[WindowKeyframes], n_cond: int, seam: int = 1) -> list[MergedKeyframe]:
    """One increasing list of the video's keyframes from every window's (see the module docstring).

    Args:
        windows: in increasing start order, each with its marked positions and their scores.
        n_cond: conditioning frames at the start of every window.
        seam: kept keyframes of different windows at most this many kept frames apart are merged.
    Returns:
        The keyframes in increasing kept-frame order.
    """
    owners = window_owners(windows, n_cond)
    kept = sorted(
        (MergedKeyframe(window.start + n_cond + position, float(score), index, position)
         for index, window in enumerate(windows)
         for position, score in zip(window.positions, window.scores, strict=True)
         if owners[window.start + n_cond + position] == index),
        key=lambda keyframe: keyframe.kept,
    )
    merged: list[MergedKeyframe] = []
    for keyframe in kept:
        previous = merged[-1] if merged else None
        if previous and keyframe.window != previous.window and keyframe.kept - previous.kept <= seam:
            if keyframe.score > previous.score:
                merged[-1] = keyframe
        else:
            merged.append(keyframe)
    return merged
