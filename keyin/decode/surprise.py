"""Surprise keyframes (paper Algorithm 3, read as in docs/architecture.md, "Baselines"): peaks of the per-step KL.

A stochastic video model's posterior KL ``s_t = KL[q(z_t | I_≤t) ‖ N(0, I)]`` is large where the
next frame is hard to predict. The first frame that reveals a direction change at vertex k is
k + 1, so a peak at clip index t marks future position ``t - n_cond + shift`` with ``shift = -1``
(``shift = 0`` is the uncorrected reading).
"""

from __future__ import annotations

import torch
from torch import Tensor


def peak_indices(scores: Tensor) -> list[int]:
    """Strict local maxima of a 1-D series; each end is compared with its one neighbour.

    A plateau (equal neighbours) is not a peak.
    """
    scores = scores.to(torch.float64)
    left = torch.cat([scores.new_full((1,), -torch.inf), scores[:-1]])
    right = torch.cat([scores[1:], scores.new_full((1,), -torch.inf)])
    return ((scores > left) & (scores > right)).nonzero().flatten().tolist()


def surprise_positions(scores: Tensor, n_keyframes: int, first: int, count: int) -> list[int]:
    """The M most surprising steps among ``first … first + count - 1``, peaks first.

    Peaks are found on the whole series (so a window edge inside the clip compares with its real
    neighbour); if fewer than M peaks fall in the window, the largest remaining steps fill up.

    Args:
        scores: (T,) per-step surprise.
        n_keyframes: M.
        first, count: the window of candidate steps.
    Returns:
        Up to M step indices, in increasing order.
    """
    window = range(max(first, 0), min(first + count, len(scores)))
    peaks = [t for t in peak_indices(scores) if t in window]
    chosen = sorted(peaks, key=lambda t: -float(scores[t]))[:n_keyframes]
    rest = sorted((t for t in window if t not in chosen), key=lambda t: -float(scores[t]))
    chosen += rest[: n_keyframes - len(chosen)]
    return sorted(chosen)


def surprise_keyframes(
    kl: Tensor, future_length: Tensor, n_cond: int, n_keyframes: int, shift: int = -1
) -> list[list[int]]:
    """Keyframe positions of a batch from per-step KL over whole clips.

    Args:
        kl: (B, L) surprise at every clip index (conditioning frames included).
        future_length: (B,) valid future frames n_b.
        n_cond: conditioning frames at the start of each clip.
        n_keyframes: M.
        shift: added to a peak's future index (docs/architecture.md, "Baselines": -1).
    Returns:
        Per clip, up to M future positions in ``0 … n_b - 1``, increasing.
    """
    positions = []
    for scores, length in zip(kl, future_length.tolist()):
        # Position p = t - n_cond + shift must lie in [0, n_b).
        steps = surprise_positions(scores, n_keyframes, first=n_cond - shift, count=length)
        positions.append([t - n_cond + shift for t in steps])
    return positions
