"""Keyframe baselines that need no training (paper Table 1; docs/architecture.md, "Baselines"): Random and Constant.

Both follow the discovery interface shared by every method: called with a batch of clips
``frames`` (B, L, C, H, W) and their valid future lengths (B,), they return per clip the future
indices they mark as keyframes.
"""

from __future__ import annotations

import numpy as np
import torch


class RandomKeyframes:
    """``n_keyframes`` distinct future frames, uniform over each clip's valid future frames."""

    def __init__(self, n_keyframes: int, seed: int = 0) -> None:
        if n_keyframes < 1:
            raise ValueError(f"n_keyframes must be >= 1, got {n_keyframes}")
        self.n_keyframes = n_keyframes
        self.rng = np.random.default_rng(seed)

    def __call__(self, frames: torch.Tensor, future_length: torch.Tensor) -> list[list[int]]:
        picks = []
        for length in future_length.tolist():
            count = min(self.n_keyframes, length)
            picks.append(sorted(self.rng.choice(length, size=count, replace=False).tolist()))
        return picks


class ConstantKeyframes:
    """A keyframe every ``offset`` frames: future indices offset-1, 2·offset-1, ... < length; with
    ``n_keyframes`` only the first that many (Jumpy's pattern, which stops after M keyframes)."""

    def __init__(self, offset: int, n_keyframes: int | None = None) -> None:
        if offset < 1:
            raise ValueError(f"offset must be >= 1, got {offset}")
        if n_keyframes is not None and n_keyframes < 1:
            raise ValueError(f"n_keyframes must be >= 1 or None, got {n_keyframes}")
        self.offset, self.n_keyframes = offset, n_keyframes

    def __call__(self, frames: torch.Tensor, future_length: torch.Tensor) -> list[list[int]]:
        return [list(range(self.offset - 1, length, self.offset))[: self.n_keyframes] for length in future_length.tolist()]
