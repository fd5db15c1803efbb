"""Run any keyframe discoverer over a dataset and score it (paper Table 1)."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Callable

import torch
from rich.progress import Progress
from torch.utils.data import DataLoader, Dataset

from keyin.eval.f1 import column_scores, keyframe_lists, keyframe_scores
from keyin.io import atomic_write_text
from keyin.viz.keyframes import save_keyframe_pictures

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
    """Keyframe scores of ``discoverer`` on every clip of ``clips``: as the method gives its keyframes
    (:func:`keyin.eval.f1.keyframe_scores`) and in the information rule's two columns
    (:func:`keyin.eval.f1.column_scores`, ``f1_interior``, ``f1_with_ends``, ...)."""
    loader = DataLoader(clips, batch_size=batch_size, num_workers=num_workers, shuffle=False)
    predicted, truth, lengths = [], [], []
    with Progress(disable=not progress) as bar:
        task = bar.add_task("discovering keyframes", total=len(clips))
        for batch in loader:
            predicted.extend(discoverer(batch["frames"], batch["future_length"]))
            truth.extend(keyframe_lists(batch["keyframes"]))
            lengths.extend(batch["future_length"].tolist())
            bar.update(task, advance=len(batch["frames"]))
    return {**keyframe_scores(predicted, truth, n_future), **column_scores(predicted, truth, lengths, n_future)}


@torch.no_grad()
def save_predictions(discoverers: dict[str, Discoverer], clips: Dataset, folder: Path, count: int = 8) -> Path:
    """``predictions.json``: the true and each method's keyframes on the first ``count`` clips.

    ``keyin-report`` draws its method-comparison figure from these files.
    """
    batch = next(iter(DataLoader(clips, batch_size=min(count, len(clips)), shuffle=False)))
    record = {
        "clips": list(range(len(batch["frames"]))),
        "truth": keyframe_lists(batch["keyframes"]),
        "predicted": {name: find(batch["frames"], batch["future_length"]) for name, find in discoverers.items()},
    }
    path = Path(folder) / "predictions.json"
    atomic_write_text(path, json.dumps(record))
    return path


@torch.no_grad()
def save_examples(discoverer: Discoverer, clips: Dataset, n_cond: int, folder: Path, count: int = 8) -> Path:
    """Pictures of the first ``count`` clips with true and discovered keyframes (``keyframes.png/.gif``)."""
    batch = next(iter(DataLoader(clips, batch_size=min(count, len(clips)), shuffle=False)))
    predicted = discoverer(batch["frames"], batch["future_length"])
    truth = keyframe_lists(batch["keyframes"])
    png, _ = save_keyframe_pictures(folder, batch["frames"], n_cond, truth, predicted)
    return png


def score_methods(
    discoverers: dict[str, Discoverer],
    clips: Dataset,
    n_cond: int,
    n_future: int,
    folder: Path,
    **loader: Any,
) -> dict[str, Any]:
    """Score every discoverer, save pictures of the first and everyone's example predictions.

    Args:
        discoverers: method name → discoverer; the first is the method, the rest its variants.
        loader: ``batch_size``, ``num_workers``, ``progress`` for :func:`evaluate_discoverer`.
    Returns:
        The first method's scores with ``method`` and, if there are more, ``variants``
        (name → scores).
    """
    scores = {name: evaluate_discoverer(find, clips, n_future, **loader) for name, find in discoverers.items()}
    (method, main), *others = scores.items()
    save_examples(discoverers[method], clips, n_cond, folder)
    save_predictions(discoverers, clips, folder)
    metrics: dict[str, Any] = dict(main, method=method)
    if others:
        metrics["variants"] = dict(others)
    return metrics
