"""The paper's keyframe readout (paper §3.1): positions as the sums of argmax offsets."""

from __future__ import annotations

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
