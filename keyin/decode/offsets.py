"""The paper's keyframe readout (§3.9, REFERENCE §3.9): positions as the sums of argmax offsets."""

from __future__ import annotations

from torch import Tensor

from keyin.losses.soft_keyframe import argmax_positions


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
