"""The paper's keyframe readout (paper §3.1): positions as the sums of argmax offsets."""

from __future__ import annotations

import torch
from torch import Tensor

from keyin.models.positions import argmax_positions, position_distributions


def offset_keyframes(offset_probs: Tensor, future_length: Tensor) -> list[list[int]]:
    """Keyframe positions of the most likely offsets, those inside each clip's valid frames.

    Args:
        offset_probs: (B, M, S) offset distributions δ; entry a is the probability of offset a + 1.
        future_length: (B,) valid future frames.
    Returns:
        Per clip, the increasing positions ``Σ_{i≤m} argmax δ_i - 1`` that are ``< length``.
    """
    positions = argmax_positions(offset_probs).cpu()
    return [[p for p in row.tolist() if p < length] for row, length in zip(positions, future_length.tolist())]


def keyframe_probabilities(offset_probs: Tensor, n_future: int) -> Tensor:
    """The probability that a keyframe sits at each future position under δ (paper Alg. 2).

    Keyframes sit at strictly increasing positions, so "keyframe t at j" are disjoint events over
    t and their probabilities ``D^t[j + 1]`` add up to the probability of a keyframe at j.

    Args:
        offset_probs: (B, M, S) offset distributions δ.
        n_future: N.
    Returns:
        (B, N) ``Σ_t D^t[j + 1]`` in [0, 1].
    """
    keyframe_pos, _ = position_distributions(offset_probs)  # (B, M, L_ext)
    return keyframe_pos[..., 1 : n_future + 1].sum(1).clamp(0.0, 1.0)


def joint_offset_keyframes(log_offsets: Tensor, future_length: Tensor) -> list[list[int]]:
    """Keyframe positions of the jointly most likely offsets under δ (our readout, "joint").

    The paper's readout takes each δ^t's argmax in turn; this one maximises the path's
    ``Σ_t log δ^t(o_t | keyframe t - 1's place)`` exactly (Viterbi over the places), stopping at
    the first keyframe that leaves the clip (its offset counts, the ones after it do not) or at M.

    Args:
        log_offsets: (B, M, L_ext, S) log δ^{t+1}(offset a + 1 | keyframe t at extended index k)
            (:meth:`keyin.models.KeyframePredictor.offset_log_probs`); K^0 is at index 0.
        future_length: (B,) valid future frames (extended indices 1 … length are inside).
    Returns:
        Per clip, the increasing positions (extended index - 1) of the keyframes inside it.
    """
    batch, n_keys, n_ext, max_offset = log_offsets.shape
    lengths = future_length.to(log_offsets.device)
    index = torch.arange(n_ext, device=log_offsets.device)
    inside = index[None] <= lengths[:, None]  # (B, L_ext): K^0 and the valid frames
    score = torch.full((batch, n_ext), float("-inf"), device=log_offsets.device)
    score[:, 0] = 0.0
    back = torch.zeros((n_keys, batch, n_ext), dtype=torch.long, device=log_offsets.device)
    best_end = torch.full((batch,), float("-inf"), device=log_offsets.device)
    end_at = torch.zeros((batch, 2), dtype=torch.long, device=log_offsets.device)  # (t, k) of the best end
    for t in range(n_keys):
        reach = torch.full((batch, n_ext, max_offset), float("-inf"), device=log_offsets.device)
        from_live = score.masked_fill(~inside, float("-inf"))[:, :, None] + log_offsets[:, t]  # (B, L_ext(k), S)
        for a in range(max_offset):  # to k + a + 1
            reach[:, a + 1 :, a] = from_live[:, : n_ext - a - 1, a]
        score, offset = reach.max(-1)  # (B, L_ext)
        back[t] = index[None] - offset - 1
        ending = score.masked_fill(inside & (t < n_keys - 1), float("-inf"))  # left the clip, or the M-th keyframe
        value, at = ending.max(-1)
        better = value > best_end
        best_end = torch.where(better, value, best_end)
        end_at[better] = torch.stack([torch.full_like(at, t), at], -1)[better]
    positions = []
    for b in range(batch):
        t, k = end_at[b].tolist()
        places = []
        while t >= 0:
            places.append(k)
            k, t = int(back[t, b, k]), t - 1
        positions.append(sorted(place - 1 for place in places if place <= int(lengths[b])))
    return positions
