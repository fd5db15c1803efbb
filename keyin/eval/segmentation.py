"""Exact best segmentation of a clip under a frozen interpolator: the stage-2 gate and a teacher.

KEYIN's stage 2 can only find keyframes that make the frozen interpolator's job easier. Given the
true frames, the best it could possibly do is the hard segmentation that minimises the summed
interpolation BCE: choose keyframes at extended indices ``0 = k_0 < k_1 < … < k_m = N`` (``k = 0``
is K^0, the last conditioning frame; ``k = j + 1`` is future position ``j``), each gap ``≤ S`` and
``m ≤ M``, interpolate every gap between the *true* boundary embeddings and score the decoded
frames. That is a shortest path over (index, count) and is solved exactly by dynamic programming.

Its F1 against the ground truth measures whether an interpolator is good enough for stage 2 to
discover the ground truth, before stage 2 is trained (PROTOTYPE-FINDINGS §4).
"""

from __future__ import annotations

from typing import Callable

import torch
import torch.nn.functional as F
from torch import Tensor

from keyin.losses.image import future_pixel_weights
from keyin.losses.soft_keyframe import IGNORE_OFFSET

SPACES = ("pixels", "embeddings")


def segment_starts_offsets(n_future: int, max_offset: int) -> tuple[Tensor, Tensor]:
    """Every segment that lies inside the clip, on the extended index.

    Returns:
        start (R,), offset (R,) int64 with ``0 <= start``, ``1 <= offset <= S``,
        ``start + offset <= N``; ordered by start, then offset.
    """
    start = torch.arange(n_future).repeat_interleave(max_offset)
    offset = torch.arange(1, max_offset + 1).repeat(n_future)
    inside = start + offset <= n_future
    return start[inside], offset[inside]


def best_segmentation(costs: Tensor, n_keyframes: int, keyframe_cost: float = 0.0) -> tuple[Tensor, list[list[int]]]:
    """Minimum-cost segmentation of ``0 … N`` into at most M gaps of at most S (exact DP).

    Args:
        costs: (B, N, S) cost of the segment from extended index ``a`` with offset ``o = s + 1``;
            ``inf`` where ``a + o > N``.
        n_keyframes: M, the most segments (keyframes) allowed.
        keyframe_cost: a price per segment (per keyframe, the closing one included). At 0 the
            optimum of an interpolation cost uses every gap it may, since a shorter segment is
            always a little easier; a price keeps only the keyframes that pay for themselves.
    Returns:
        total (B,) the minimum summed cost, and per clip the keyframe *positions* (future frame
        indices ``k - 1``) of the interior boundaries, the final boundary at ``N - 1`` excluded.
    Raises:
        ValueError: if M·S < N (no segmentation exists).
    """
    batch, n_future, max_offset = costs.shape
    if n_keyframes * max_offset < n_future:
        raise ValueError(f"M*S = {n_keyframes * max_offset} cannot cover N = {n_future}")
    costs = costs.cpu() + keyframe_cost
    # best[m, b, k]: cheapest cover of 0…k by exactly m gaps; back[m, b, k]: the gap's offset.
    best = torch.full((n_keyframes + 1, batch, n_future + 1), float("inf"), dtype=costs.dtype)
    back = torch.zeros((n_keyframes + 1, batch, n_future + 1), dtype=torch.long)
    best[0, :, 0] = 0.0
    for m in range(1, n_keyframes + 1):
        for k in range(1, n_future + 1):
            offsets = torch.arange(1, min(max_offset, k) + 1)  # gap ending at k
            candidates = best[m - 1][:, k - offsets] + costs[:, k - offsets, offsets - 1]  # (B, o)
            best[m, :, k], arg = candidates.min(dim=1)
            back[m, :, k] = offsets[arg]
    total, n_gaps = best[:, :, n_future].min(dim=0)  # over m
    positions: list[list[int]] = []
    for b in range(batch):
        k, m, boundaries = n_future, int(n_gaps[b]), []
        while m > 0:
            boundaries.append(k)
            k -= int(back[m, b, k])
            m -= 1
        positions.append(sorted(index - 1 for index in boundaries if index < n_future))
    return total, positions


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


def boundary_keyframes(scores: Tensor, lengths: Tensor, n_keyframes: int, max_offset: int) -> list[list[int]]:
    """The most likely keyframe positions under per-frame boundary scores, at most M gaps of at most S.

    Args:
        scores: (B, N) boundary logits; lengths: (B,) valid future frames.
    Returns:
        Per clip, the interior keyframe positions (the clip's last frame is never one).
    """
    return decode_by_length(
        lambda rows, length: boundary_segment_costs(scores[rows, :length].detach().float(), max_offset),
        lengths, n_keyframes, max_offset,
    )


def decode_by_length(
    segment_costs: Callable[[Tensor, int], Tensor],
    lengths: Tensor,
    n_keyframes: int,
    max_offset: int,
    keyframe_cost: float = 0.0,
) -> list[list[int]]:
    """Best segmentation of clips of different valid lengths, each closing at its own last frame.

    Args:
        segment_costs: ``(rows, length) -> (R, length, S)`` costs of the clips ``rows`` (all of
            valid length ``length``), cut to that length.
        lengths: (B,) valid future frames.
        keyframe_cost: see :func:`best_segmentation`.
    Returns:
        Per clip, the interior keyframe positions.
    """
    positions: list[list[int]] = [[] for _ in range(len(lengths))]
    for length in lengths.unique().tolist():
        if length < 1:
            continue
        if n_keyframes * max_offset < length:
            raise ValueError(f"M*S = {n_keyframes * max_offset} cannot cover a clip of {length} frames")
        rows = (lengths == length).nonzero().flatten()
        _, decoded = best_segmentation(segment_costs(rows, length), n_keyframes, keyframe_cost)
        for row, clip_positions in zip(rows.tolist(), decoded):
            positions[row] = clip_positions
    return positions


def with_sequence_ends(positions: list[list[int]], lengths: Tensor, n_future: int) -> list[list[int]]:
    """Add the last valid frame of every clip that ends inside the window as a keyframe.

    A segmentation closes each clip at its last valid frame. Where the sequence ends before N
    (a demonstration that finished: the rest is padding) that closing boundary is the end of the
    last subgoal, a keyframe of the data; where the clip fills the window, the window cut the
    sequence and its last frame is no event. Full-length datasets (Brownian) are unchanged.

    Args:
        positions: per clip, interior keyframe positions; lengths: (B,) valid future frames.
    Returns:
        Per clip, the positions with ``length - 1`` appended for clips with ``0 < length < n_future``.
    """
    return [
        row + [length - 1] if 0 < length < n_future else row
        for row, length in zip(positions, lengths.tolist())
    ]


@torch.no_grad()
def map_keyframes(
    interpolator: torch.nn.Module,
    decoder: torch.nn.Module,
    boundary_emb: Tensor,
    frames: Tensor,
    lengths: Tensor,
    n_keyframes: int,
    keyframe_cost: float,
    scores: Tensor | None = None,
    boundary_weight: float = 0.0,
    weights: Tensor | None = None,
) -> list[list[int]]:
    """The most likely keyframes given the frames: interpolation BCE, a price per keyframe and,
    optionally, the keyframe predictor's boundary scores as a prior.

    Minimises ``Σ_segments BCE + keyframe_cost · (#keyframes) − boundary_weight · Σ_keyframes s``
    exactly (our discovery rule "map", docs/decisions.md).

    Args:
        boundary_emb: (B, N + 1, E) embeddings on the extended index; frames: (B, N, D) in [0, 1].
        lengths: (B,) valid future frames.
        scores: (B, N) boundary logits, or None for the interpolation cost alone.
        weights: (B, N, D) pixel weights of the frames, None for the plain BCE.
    Returns:
        Per clip, the interior keyframe positions.
    """
    max_offset = interpolator.max_offset

    def segment_costs(rows: Tensor, length: int) -> Tensor:
        rows = rows.to(boundary_emb.device)
        costs = interpolation_costs(
            interpolator, decoder, boundary_emb[rows, : length + 1], frames[rows, :length],
            None if weights is None else weights[rows, :length],
        )
        if scores is not None and boundary_weight:
            costs = costs + boundary_weight * boundary_segment_costs(scores[rows, :length].float(), max_offset)
        return costs  # best_segmentation moves it to the CPU

    return decode_by_length(segment_costs, lengths.cpu(), n_keyframes, max_offset, keyframe_cost)


def _gaps(row: list[int], n_future: int) -> list[tuple[int, int]]:
    """(extended start index, offset) of each gap between K^0, the positions in ``row`` and the
    closing boundary at ``N - 1``."""
    boundaries = [0, *(p + 1 for p in row), n_future]
    return [(left, right - left) for left, right in zip(boundaries[:-1], boundaries[1:])]


def path_cost(costs: Tensor, positions: list[list[int]]) -> Tensor:
    """Summed cost of given keyframe positions, closed by a final boundary at ``N - 1``.

    Args:
        costs: (B, N, S) from :func:`interpolation_costs`.
        positions: per clip, increasing future positions in ``0 … N-2``.
    Returns:
        (B,) total cost; ``inf`` where a gap exceeds S.
    """
    batch, n_future, max_offset = costs.shape
    totals = torch.zeros(batch, dtype=costs.dtype)
    for b, row in enumerate(positions):
        for left, gap in _gaps([p for p in row if p < n_future - 1], n_future):
            totals[b] += costs[b, left, gap - 1] if 1 <= gap <= max_offset else float("inf")
    return totals


class SegmentationDiscoverer:
    """Keyframes = the exact best segmentation under a trained stage-1 model (see module doc).

    Args:
        stage1: an :class:`keyin.lit.interpolator.InterpolatorModule` (frozen, eval mode).
        n_keyframes: M.
        space: "pixels" (decoded BCE, what L_inter scores) or "embeddings" (squared error of the
            interpolated embeddings, no decoding).
    """

    def __init__(self, stage1: torch.nn.Module, n_keyframes: int, space: str = "pixels") -> None:
        if space not in SPACES:
            raise ValueError(f"space must be one of {SPACES}, got {space!r}")
        self.stage1, self.n_keyframes, self.space = stage1.eval(), n_keyframes, space
        self.last_costs: Tensor | None = None

    @torch.no_grad()
    def __call__(self, clips: Tensor, future_length: Tensor) -> list[list[int]]:
        """Keyframe positions of (B, L, C, H, W) clips with (B,) valid future frames, each clip
        segmented within its own frames (:func:`with_sequence_ends` adds the end of a sequence
        that stops inside the window). ``last_costs`` keeps the (R, length, S) costs of the last
        group of equally long clips (all clips, in order, when every clip is full)."""
        n_cond = self.stage1.hparams.n_cond
        boundary_emb = self.stage1.encoder(clips)[:, n_cond - 1 :]  # (B, N + 1, E)
        frames = clips[:, n_cond:].flatten(2)
        weights = future_pixel_weights(self.stage1.pixel_weights(clips), n_cond)

        def segment_costs(rows: Tensor, length: int) -> Tensor:
            rows = rows.to(boundary_emb.device)
            if self.space == "embeddings":
                costs = embedding_costs(self.stage1.interpolator, boundary_emb[rows, : length + 1])
            else:
                costs = interpolation_costs(
                    self.stage1.interpolator, self.stage1.decoder, boundary_emb[rows, : length + 1], frames[rows, :length],
                    None if weights is None else weights[rows, :length],
                )
            self.last_costs = costs
            return costs

        lengths = future_length.cpu()
        positions = decode_by_length(segment_costs, lengths, self.n_keyframes, self.stage1.interpolator.max_offset)
        return with_sequence_ends(positions, lengths, frames.shape[1])


def segmentation_offsets(positions: list[list[int]], n_future: int, n_keyframes: int) -> Tensor:
    """Teacher offsets of the keyframes at given interior positions.

    Args:
        positions: per clip, increasing interior keyframe positions (as from
            :func:`best_segmentation`).
        n_future: N.
        n_keyframes: M.
    Returns:
        (B, M) int64 offsets in 1…S for the interior keyframes; ``IGNORE_OFFSET`` for the rest.
        The gap that closes the clip at ``N - 1`` gets no target: a keyframe there is no
        discovered keyframe (the last frame is never one, and evaluation counts it as a false
        positive), so where the chain goes after the last interior keyframe is left to the soft loss.
    """
    offsets = torch.full((len(positions), n_keyframes), IGNORE_OFFSET, dtype=torch.long)
    for b, row in enumerate(positions):
        interior = [gap for _, gap in _gaps(row, n_future)][: min(len(row), n_keyframes)]
        offsets[b, : len(interior)] = torch.tensor(interior, dtype=torch.long)
    return offsets
