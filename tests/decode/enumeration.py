"""Brute-force references for the segmentation DP: every composition of N into parts of at most S."""

import itertools

import torch

from keyin.data.segments import all_segments

INF = float("inf")


def outside_the_clip(costs: torch.Tensor) -> torch.Tensor:
    """(B, N, S) costs with inf where a segment would leave the clip (start + offset > N)."""
    _, start, offset = all_segments(1, 0, costs.shape[1], range(1, costs.shape[2] + 1))
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


def keyframe_sets(length: int, max_offset: int, n_keyframes: int) -> list[tuple[int, ...]]:
    """Every set of interior keyframe positions that cuts 0 … length into at most M gaps of at most S."""
    def covers(chosen: tuple[int, ...]) -> bool:
        edges = [0, *(p + 1 for p in chosen), length]
        return max(b - a for a, b in zip(edges[:-1], edges[1:])) <= max_offset

    return [chosen for size in range(n_keyframes) for chosen in itertools.combinations(range(length - 1), size)
            if covers(chosen)]


def cheapest_keyframes(bce: torch.Tensor, scores: torch.Tensor, sets: list[tuple[int, ...]], length: int,
                       price: float, weight: float) -> list[int]:
    """Of ``sets``, the keyframes of least summed segment BCE (N, S) + ``price`` per gap − ``weight`` · scores (N,)."""
    def total(chosen: tuple[int, ...]) -> float:
        edges = [0, *(p + 1 for p in chosen), length]
        cost = sum(float(bce[left, right - left - 1]) + price for left, right in zip(edges[:-1], edges[1:]))
        return cost - weight * sum(float(scores[p]) for p in chosen)

    return list(min(sets, key=total))


def random_map_inputs(batch: int, n_future: int, max_offset: int, seed: int, embed_dim: int = 8):
    """An untrained interpolator and decoder, (B, N + 1, E) boundary embeddings, (B, N, 64) binary frames
    and (B, N) boundary scores, for brute-force checks of ``map``."""
    from keyin.models import ConvDecoder, Interpolator

    torch.manual_seed(seed)
    interpolator = Interpolator(embed_dim, max_offset, 0, 16, 1, 16).eval()
    decoder = ConvDecoder(8, 1, 4, embed_dim, norm="none").eval()
    boundary_emb = torch.rand(batch, n_future + 1, embed_dim)
    frames = (torch.rand(batch, n_future, 64) > 0.5).float()
    return interpolator, decoder, boundary_emb, frames, torch.randn(batch, n_future) * 20
