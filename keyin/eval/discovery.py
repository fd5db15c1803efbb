"""Run any keyframe discoverer over a dataset and score it (paper Table 1)."""

from __future__ import annotations

from typing import Callable

import torch
from rich.progress import Progress
from torch.utils.data import DataLoader, Dataset

from keyin.eval.f1 import keyframe_scores

Discoverer = Callable[[torch.Tensor, torch.Tensor], list[list[int]]]


@torch.no_grad()
def evaluate_discoverer(
    discoverer: Discoverer,
    clips: Dataset,
    n_future: int,
    batch_size: int = 100,
    num_workers: int = 0,
    progress: bool = False,
) -> dict[str, float]:
    """Keyframe scores of ``discoverer`` on every clip of ``clips`` (see ``keyframe_scores``)."""
    loader = DataLoader(clips, batch_size=batch_size, num_workers=num_workers, shuffle=False)
    predicted, truth = [], []
    with Progress(disable=not progress) as bar:
        task = bar.add_task("discovering keyframes", total=len(clips))
        for batch in loader:
            predicted.extend(discoverer(batch["frames"], batch["future_length"]))
            truth.extend(torch.nonzero(row).flatten().tolist() for row in batch["keyframes"])
            bar.update(task, advance=len(batch["frames"]))
    return keyframe_scores(predicted, truth, n_future)
