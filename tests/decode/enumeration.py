"""Brute-force references for the segmentation DP: every composition of N into parts of at most S."""

import itertools

import torch

from keyin.decode.segmentation import segment_starts_offsets

INF = float("inf")


def outside_the_clip(costs: torch.Tensor) -> torch.Tensor:
    """(B, N, S) costs with inf where a segment would leave the clip (start + offset > N)."""
    start, offset = segment_starts_offsets(*costs.shape[1:])
    inside = torch.zeros(costs.shape[1:], dtype=torch.bool)
    inside[start, offset - 1] = True
    return costs.masked_fill(~inside, INF)


def cheapest_by_count(costs: torch.Tensor, n_keyframes: int) -> dict[int, tuple[float, list[int]]]:
    """Enumerate every composition of N into m parts of at most S: the cheapest per m."""
    n_future, max_offset = costs.shape
    best: dict[int, tuple[float, list[int]]] = {}
    for m in range(1, n_keyframes + 1):
        for gaps in itertools.product(range(1, max_offset + 1), repeat=m):
            if sum(gaps) == n_future:
                boundaries = [0, *itertools.accumulate(gaps)]
                total = sum(float(costs[a, g - 1]) for a, g in zip(boundaries[:-1], gaps))
                if total < best.get(m, (INF,))[0]:
                    best[m] = (total, [k - 1 for k in boundaries[1:-1]])
    return best


def brute_force(costs: torch.Tensor, n_keyframes: int, keyframe_cost: float = 0.0) -> tuple[float, list[int]]:
    """The cheapest composition into at most M parts, each part priced ``keyframe_cost``."""
    by_count = cheapest_by_count(costs, n_keyframes)
    best = min(by_count, key=lambda m: by_count[m][0] + m * keyframe_cost)
    return by_count[best][0] + best * keyframe_cost, by_count[best][1]
