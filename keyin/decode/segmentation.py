"""Exact best segmentation of a clip (dynamic programming): the core of KEYIN's decodings.

Keyframes at extended indices ``0 = k_0 < k_1 < … < k_m = N`` (``k = 0`` is K^0, the last
conditioning frame; ``k = j + 1`` is future position ``j``), each gap ``≤ S`` and ``m ≤ M``: the
segmentation of least summed segment cost is a shortest path over (index, count), solved exactly.
The segment costs come from :mod:`keyin.decode.segment_costs`; the rules that use them (the
teacher, ``boundaries``, ``map``, the stage-1 gate) from :mod:`keyin.decode.rules`.
"""

from __future__ import annotations

from typing import Callable

import torch
from torch import Tensor

from keyin.decode.prices import KNEE
from keyin.losses.soft_keyframe import IGNORE_OFFSET


KeyframeCost = float | str  # nats per keyframe, or KNEE


def count_tables(costs: Tensor, n_keyframes: int) -> tuple[Tensor, Tensor]:
    """The DP over (count, index): ``best[m, b, k]`` the cheapest cover of 0…k by exactly m gaps
    (inf where none), ``back[m, b, k]`` the offset of its last gap; both (M + 1, B, N + 1)."""
    batch, n_future, max_offset = costs.shape
    best = torch.full((n_keyframes + 1, batch, n_future + 1), float("inf"), dtype=costs.dtype)
    back = torch.zeros((n_keyframes + 1, batch, n_future + 1), dtype=torch.long)
    best[0, :, 0] = 0.0
    for m in range(1, n_keyframes + 1):
        for k in range(1, n_future + 1):
            offsets = torch.arange(1, min(max_offset, k) + 1)  # gap ending at k
            candidates = best[m - 1][:, k - offsets] + costs[:, k - offsets, offsets - 1]  # (B, o)
            best[m, :, k], arg = candidates.min(dim=1)
            back[m, :, k] = offsets[arg]
    return best, back


def knee_counts(totals: Tensor) -> Tensor:
    """Per clip, the number of gaps at the knee of its cost curve (label-free, our rule).

    With ``g(m) = C(m - 1) - C(m)`` what the m-th gap saves (and ``g = 0`` past the most feasible
    gaps), the knee is the m after which the saving falls the most, ``argmax g(m) - g(m + 1)`` over
    the feasible m above the fewest: the last keyframe before adding one stops paying. It needs no
    scale (no price in nats) and no labels; it never picks the fewest feasible gaps unless that is
    the only count.

    Args:
        totals: (B, M + 1) the cheapest cost with exactly m gaps, inf where m gaps cannot cover.
    Returns:
        (B,) int64 counts; ties go to the fewer gaps.
    """
    feasible = totals.isfinite()
    savings = torch.zeros_like(totals)
    savings[:, 1:] = torch.where(feasible[:, 1:] & feasible[:, :-1], totals[:, :-1] - totals[:, 1:], 0.0)
    falls = savings - torch.cat([savings[:, 1:], torch.zeros_like(savings[:, :1])], dim=1)  # g(m) - g(m + 1)
    candidates = feasible & torch.cat([torch.zeros_like(feasible[:, :1]), feasible[:, :-1]], dim=1)
    only = feasible.long().argmax(1)  # the fewest feasible gaps, where nothing else is feasible
    best = torch.where(candidates, falls, -float("inf")).argmax(1)
    return torch.where(candidates.any(1), best, only)


def best_segmentation(
    costs: Tensor, n_keyframes: int, keyframe_cost: KeyframeCost = 0.0
) -> tuple[Tensor, list[list[int]]]:
    """Minimum-cost segmentation of ``0 … N`` into at most M gaps of at most S (exact DP).

    Args:
        costs: (B, N, S) cost of the segment from extended index ``a`` with offset ``o = s + 1``;
            ``inf`` where ``a + o > N``.
        n_keyframes: M, the most segments (keyframes) allowed.
        keyframe_cost: a price per segment (per keyframe, the closing one included). At 0 the
            optimum of an interpolation cost uses every gap it may, since a shorter segment is
            always a little easier; a price keeps only the keyframes that pay for themselves.
            ``"knee"`` (:data:`KNEE`): no price; each clip gets the best segmentation with the
            number of gaps of :func:`knee_counts`.
    Returns:
        total (B,) the summed cost of the chosen segmentation (prices included), and per clip the
        keyframe *positions* (future frame indices ``k - 1``) of the interior boundaries, the final
        boundary at ``N - 1`` excluded.
    Raises:
        ValueError: if M·S < N (no segmentation exists), or for a price that is neither a number nor "knee".
    """
    batch, n_future, max_offset = costs.shape
    if n_keyframes * max_offset < n_future:
        raise ValueError(f"M*S = {n_keyframes * max_offset} cannot cover N = {n_future}")
    if isinstance(keyframe_cost, str) and keyframe_cost != KNEE:
        raise ValueError(f"keyframe_cost must be a number (nats per keyframe) or {KNEE!r}, got {keyframe_cost!r}")
    price = 0.0 if keyframe_cost == KNEE else float(keyframe_cost)
    best, back = count_tables(costs.cpu() + price, n_keyframes)
    if keyframe_cost == KNEE:
        n_gaps = knee_counts(best[:, :, n_future].T)
        total = best[:, :, n_future].T.gather(1, n_gaps[:, None]).squeeze(1)
    else:
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


def decode_by_length(
    segment_costs: Callable[[Tensor, int], Tensor],
    lengths: Tensor,
    n_keyframes: int,
    max_offset: int,
    keyframe_cost: KeyframeCost = 0.0,
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


def segmentation_offsets(
    positions: list[list[int]], lengths: list[int], n_keyframes: int, max_offset: int, leave: bool = False
) -> Tensor:
    """Teacher offsets of the keyframes at given interior positions (and, with ``leave``, of the one
    that leaves the clip).

    Args:
        positions: per clip, increasing interior keyframe positions (as from
            :func:`best_segmentation`).
        lengths: per clip, its valid future frames.
        n_keyframes: M.
        max_offset: S.
        leave: also teach the keyframe after the last interior one the offset that puts it just past
            the clip's last valid frame (where the argmax readout drops it), where S allows; without
            it, where the chain goes after the last interior keyframe is left to the soft loss (the
            gap closing at the last frame is no keyframe: the last frame is never one).
    Returns:
        (B, M) int64 offsets in 1…S; ``IGNORE_OFFSET`` for the keyframes without a target.
    """
    offsets = torch.full((len(positions), n_keyframes), IGNORE_OFFSET, dtype=torch.long)
    for b, (row, length) in enumerate(zip(positions, lengths)):
        interior = [gap for _, gap in _gaps(row, length)][: min(len(row), n_keyframes)]
        leaving = length + 1 - (row[len(interior) - 1] + 1 if interior else 0)  # to extended index length + 1
        if leave and len(interior) < n_keyframes and leaving <= max_offset:
            interior.append(leaving)
        offsets[b, : len(interior)] = torch.tensor(interior, dtype=torch.long)
    return offsets
