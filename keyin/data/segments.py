"""Segments for training and diagnosing the interpolator (stage 1, paper §3.2 "Training procedure", §4).

A segment of a clip is a start frame ``a`` and an offset ``o``: the interpolator sees frames ``a``
and ``a + o`` and must produce frames ``a + 1 … a + o`` (output ``i`` sits at ``a + 1 + i``; the
last output is the end keyframe itself).
"""

from __future__ import annotations

import torch


def partition_segments(
    lengths: torch.Tensor, offset_min: int, offset_max: int, generator: torch.Generator
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Cut every clip into consecutive segments with offsets uniform in [offset_min, offset_max].

    Each clip starts its partition at a random frame in [0, offset_max) so that every frame is
    an endpoint as often as any other; the partition stops before it would leave the clip's valid
    frames (padding never enters a segment).

    Args:
        lengths: (B,) valid frames of each clip (conditioning + valid future frames).
    Returns:
        clip (R,), start (R,), offset (R,) int64 for the R segments of the whole batch.
    """
    batch, longest = len(lengths), int(lengths.max()) // offset_min + 1
    offsets = torch.randint(offset_min, offset_max + 1, (batch, longest), generator=generator)
    first = torch.randint(0, offset_max, (batch, 1), generator=generator)
    ends = first + offsets.cumsum(dim=1)
    starts = ends - offsets
    inside = ends <= lengths.cpu()[:, None] - 1
    clip = torch.arange(batch)[:, None].expand_as(offsets)
    return clip[inside], starts[inside], offsets[inside]


def all_segments(
    batch: int, first: int, last: int, offsets: range
) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
    """Every segment with an offset in ``offsets`` whose frames lie in [first, last], for every clip.

    The one enumeration of segments: stage 1's per-offset diagnostics (frames on the clip axis) and
    the exact segmentation's costs (``first = 0``, ``last = N`` on the extended index) both read it.

    Returns:
        clip (R,), start (R,), offset (R,) int64, ordered by clip, then start, then offset.
    """
    starts = torch.arange(first, last).repeat_interleave(len(offsets))
    steps = torch.tensor(offsets).repeat(max(last - first, 0))
    inside = starts + steps <= last
    start, offset = starts[inside], steps[inside]
    clip = torch.arange(batch).repeat_interleave(len(start))
    return clip, start.repeat(batch), offset.repeat(batch)


def segment_frames(start: torch.Tensor, offset: torch.Tensor, max_offset: int) -> tuple[torch.Tensor, torch.Tensor]:
    """Frame indices of each segment's S outputs and which of them exist.

    Args:
        start, offset: (R,).
    Returns:
        frames (R, S) int64 (clamped into the segment for outputs that do not exist),
        valid (R, S) bool, True for outputs i < offset.
    """
    steps = torch.arange(max_offset, device=offset.device)
    valid = steps[None, :] < offset[:, None]
    frames = start[:, None] + 1 + torch.minimum(steps[None, :], offset[:, None] - 1)
    return frames, valid


def crosses_keyframe(
    keyframes: torch.Tensor, clip: torch.Tensor, start: torch.Tensor, offset: torch.Tensor
) -> torch.Tensor:
    """Whether a ground-truth keyframe lies strictly inside each segment (a "bent" segment).

    Args:
        keyframes: (B, L) bool on the clip axis.
        clip, start, offset: (R,).
    Returns:
        (R,) bool.
    """
    counts = torch.nn.functional.pad(keyframes.long().cumsum(dim=1), (1, 0))  # (B, L + 1)
    inside = counts[clip, start + offset] - counts[clip, start + 1]
    return inside > 0


def valid_frames(lengths: torch.Tensor, n_frames: int) -> torch.Tensor:
    """(B, L) True at the first ``lengths`` (B,) frames of each clip, False on the padding after."""
    return torch.arange(n_frames, device=lengths.device)[None] < lengths[:, None]
