"""TAP on the test split (paper §4.2; docs/baselines.md): its loss between each clip's first and last valid frame,
where in time its predictions land, and a picture of them. TAP finds no keyframes, so it has no
keyframe F1; these are its metrics."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import torch
from torch.utils.data import DataLoader, Dataset

from keyin.losses.tap import argmin_times, pair_images, whole_clip_pairs
from keyin.viz.keyframes import save_keyframe_pictures

PairTerms = Callable[[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor], tuple[torch.Tensor, torch.Tensor]]
"""(frames (B, L, C, H, W), n_valid, start, goal (B,)) → min-over-time loss (B,) and argmin (B,)."""
Subgoal = Callable[[torch.Tensor, torch.Tensor], torch.Tensor]
"""(start, goal images (B, C, H, W)) → predicted images (B, C, H, W) in [0, 1]."""


@torch.no_grad()
def score_whole_clips(
    terms: PairTerms, clips: Dataset, n_cond: int, margin: int, batch_size: int = 100
) -> dict[str, float | int]:
    """Mean min-over-time BCE per pixel with (a, b) = (first, last valid frame) over ``clips``.

    Returns:
        ``bce_per_pixel``; ``argmin_relative``, the mean (t - a) / (b - a) of the chosen frames;
        ``argmin_last``, the fraction of them at the last admissible frame; ``argmin_middle``, the
        fraction in the middle third (1/3 ≤ (t - a) / (b - a) ≤ 2/3); ``argmin_deciles``, the fraction
        in each tenth of [0, 1] (:func:`landing_deciles`); ``n_sequences``.
    """
    losses, relative, at_last = [], [], []
    for batch in DataLoader(clips, batch_size=batch_size, shuffle=False):
        n_valid = n_cond + batch["future_length"]
        start, goal = whole_clip_pairs(n_valid)
        loss, argmin = terms(batch["frames"], n_valid, start, goal)
        clip_relative, clip_last = argmin_times(argmin.cpu(), start, goal, margin)
        losses.append(loss.cpu())
        relative.append(clip_relative)
        at_last.append(clip_last)
    pixels, relative = batch["frames"][0, 0].numel(), torch.cat(relative)
    return {
        "bce_per_pixel": float(torch.cat(losses).mean()) / pixels,
        "argmin_relative": float(relative.mean()),
        "argmin_last": float(torch.cat(at_last).float().mean()),
        "argmin_middle": float(((relative >= 1 / 3) & (relative <= 2 / 3)).float().mean()),
        "argmin_deciles": landing_deciles(relative),
        "n_sequences": len(clips),
    }


def landing_deciles(relative: torch.Tensor) -> list[float]:
    """The fraction of (B,) relative times (t - a) / (b - a) in (0, 1) in each tenth [k/10, (k+1)/10)."""
    counts = torch.bincount((relative * 10).floor().long().clamp(0, 9), minlength=10)
    return [round(float(count) / len(relative), 4) for count in counts]


@torch.no_grad()
def save_subgoal_grid(subgoal: Subgoal, clips: Dataset, n_cond: int, folder: Path, count: int = 8) -> Path:
    """``tap_grid.png`` (and ``.gif``): one row per test clip, its first frame (grey border), the
    prediction between it and the last valid frame (red border), and that last frame.

    Returns:
        The PNG's path.
    """
    batch = next(iter(DataLoader(clips, batch_size=min(count, len(clips)), shuffle=False)))
    start_images, goal_images = pair_images(batch["frames"], *whole_clip_pairs(n_cond + batch["future_length"]))
    predicted = subgoal(start_images, goal_images).cpu()
    rows = torch.stack([start_images, predicted, goal_images], dim=1)  # (K, 3, C, H, W)
    no_keyframes, prediction = [[] for _ in rows], [[0] for _ in rows]
    png, _ = save_keyframe_pictures(folder, rows, 1, no_keyframes, prediction, name="tap_grid")
    return png
