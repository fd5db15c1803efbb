"""Segment costs for the exact segmentation (:mod:`keyin.decode.segmentation`).

Every in-clip segment of a clip scored by how badly the frozen interpolator renders it between the
*true* boundary embeddings (pixel BCE, or the cheap squared embedding error), or by per-frame
boundary scores so that the best segmentation is their most likely boundary set.
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import Tensor

from keyin.decode.segmentation import segment_starts_offsets


def _all_segments(batch: int, n_future: int, max_offset: int) -> tuple[Tensor, Tensor, Tensor]:
    """clip, start, offset (R,) of every in-clip segment of every clip."""
    start, offset = segment_starts_offsets(n_future, max_offset)
    clip = torch.arange(batch).repeat_interleave(len(start))
    return clip, start.repeat(batch), offset.repeat(batch)


def _interpolate(interpolator: torch.nn.Module, boundary_emb: Tensor, clip: Tensor, start: Tensor, offset: Tensor) -> Tensor:
    """(R, S, E) interpolation between the true boundary embeddings, z = 0."""
    z = boundary_emb.new_zeros(len(clip), interpolator.latent_dim)
    onehot = F.one_hot(offset - 1, interpolator.max_offset).to(boundary_emb)
    return interpolator(boundary_emb[clip, start], boundary_emb[clip, start + offset], onehot, z)


def _output_positions(start: Tensor, offset: Tensor, max_offset: int, n_future: int) -> tuple[Tensor, Tensor]:
    """Future positions ``a … a+o-1`` of each segment's outputs (R, S) and which exist (R, S)."""
    steps = torch.arange(max_offset, device=start.device)
    valid = steps[None, :] < offset[:, None]
    return (start[:, None] + steps[None, :]).clamp(max=n_future - 1), valid


@torch.no_grad()
def interpolation_costs(
    interpolator: torch.nn.Module,
    decoder: torch.nn.Module,
    boundary_emb: Tensor,
    frames: Tensor,
    weights: Tensor | None = None,
    chunk: int = 1024,
) -> Tensor:
    """Summed pixel BCE of interpolating every in-clip segment between true boundary embeddings.

    Args:
        interpolator: a :class:`keyin.models.Interpolator`, run with z = 0.
        decoder: the decoder it was trained with (returns logits).
        boundary_emb: (B, N + 1, E) embeddings on the extended index (K^0, then the N future frames).
        frames: (B, N, D) the future frames in [0, 1], flattened.
        weights: (B, N, D) their pixel weights (keyin/losses/image.py), None for the plain BCE.
        chunk: segments per interpolator/decoder call.
    Returns:
        (B, N, S) costs, ``inf`` where the segment leaves the clip.
    """
    batch, n_ext, _ = boundary_emb.shape
    n_future, max_offset, device = n_ext - 1, interpolator.max_offset, boundary_emb.device
    costs = torch.full((batch, n_future, max_offset), float("inf"), device=device)
    clip, start, offset = (index.to(device) for index in _all_segments(batch, n_future, max_offset))
    for first in range(0, len(clip), chunk):
        c, a, o = clip[first : first + chunk], start[first : first + chunk], offset[first : first + chunk]
        predicted = _interpolate(interpolator, boundary_emb, c, a, o)  # (R, S, E)
        positions, valid = _output_positions(a, o, max_offset, n_future)
        logits = decoder(predicted[valid]).flatten(1)  # (V, D)
        rows = c[:, None].expand_as(positions)[valid]
        targets = frames[rows, positions[valid]]
        pixel_weights = None if weights is None else weights[rows, positions[valid]]
        bce = F.binary_cross_entropy_with_logits(logits, targets, pixel_weights, reduction="none").sum(1)
        costs[c, a, o - 1] = bce.new_zeros(len(c)).index_put_((valid.nonzero()[:, 0],), bce, accumulate=True)
    return costs


@torch.no_grad()
def embedding_costs(interpolator: torch.nn.Module, boundary_emb: Tensor) -> Tensor:
    """Summed squared embedding error of every in-clip segment: the decoder-free, cheap variant.

    Args:
        interpolator: a :class:`keyin.models.Interpolator`, run with z = 0.
        boundary_emb: (B, N + 1, E) embeddings on the extended index.
    Returns:
        (B, N, S) costs, ``inf`` where the segment leaves the clip.
    """
    batch, n_ext, _ = boundary_emb.shape
    n_future, max_offset = n_ext - 1, interpolator.max_offset
    clip, start, offset = _all_segments(batch, n_future, max_offset)
    clip, start, offset = clip.to(boundary_emb.device), start.to(boundary_emb.device), offset.to(boundary_emb.device)
    predicted = _interpolate(interpolator, boundary_emb, clip, start, offset)  # (R, S, E)
    positions, valid = _output_positions(start, offset, max_offset, n_future)
    targets = boundary_emb[clip[:, None], positions + 1]  # (R, S, E): future position p is index p + 1
    per_segment = (((predicted - targets) ** 2).sum(-1) * valid).sum(-1)  # (R,)
    costs = boundary_emb.new_full((batch, n_future, max_offset), float("inf"))
    costs[clip, start, offset - 1] = per_segment
    return costs


def boundary_segment_costs(scores: Tensor, max_offset: int) -> Tensor:
    """Segment costs under which the best segmentation is the MAP of per-frame boundary scores.

    With boundary probability ``p_j = σ(s_j)`` per future position, the log-likelihood of a set of
    interior boundaries is ``Σ_boundaries log p + Σ_others log(1 - p)``; up to a constant, each
    boundary adds its logit ``s_j``. A segment ending at extended index ``e < N`` (position
    ``e - 1``) therefore costs ``-s[e - 1]``; the segment closing the clip at ``N`` costs nothing.

    Args:
        scores: (B, N) boundary logits of the future positions.
        max_offset: S.
    Returns:
        (B, N, S) costs for :func:`best_segmentation`, ``inf`` where a segment leaves the clip.
    """
    batch, n_future = scores.shape
    start, offset = (index.to(scores.device) for index in segment_starts_offsets(n_future, max_offset))
    end = start + offset  # extended index of the segment's closing boundary
    per_segment = torch.where(end < n_future, -scores[:, (end - 1).clamp(max=n_future - 1)], scores.new_zeros(()))
    costs = scores.new_full((batch, n_future, max_offset), float("inf"))
    costs[:, start, offset - 1] = per_segment
    return costs
