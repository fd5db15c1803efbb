"""Run any keyframe discoverer over a dataset and score it (paper Table 1)."""

from __future__ import annotations

import csv
import io
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import torch
from rich.progress import Progress
from torch.utils.data import DataLoader, Dataset

from keyin.eval.f1 import column_scores, keyframe_lists, keyframe_scores, video_scores
from keyin.io import atomic_write_text
from keyin.viz.keyframes import save_keyframe_pictures

Discoverer = Callable[[torch.Tensor, torch.Tensor], list[list[int]]]


@dataclass
class Discovered:
    """A discoverer's keyframes on every clip of a dataset, beside the labels: per clip, future indices."""

    predicted: list[list[int]]
    truth: list[list[int]]
    lengths: list[int]  # valid future frames

    def scores(self, n_future: int, tolerances: Sequence[int] = (1,)) -> dict[str, float]:
        """As the method gives its keyframes (:func:`keyin.eval.f1.keyframe_scores`) and in the
        information rule's two columns (:func:`keyin.eval.f1.column_scores`, ``f1_interior``, ...)."""
        return {
            **keyframe_scores(self.predicted, self.truth, n_future, tolerances),
            **column_scores(self.predicted, self.truth, self.lengths, n_future),
        }


@torch.no_grad()
def discover(
    discoverer: Discoverer, clips: Dataset, batch_size: int = 100, num_workers: int = 0, progress: bool = False
) -> Discovered:
    """Run ``discoverer`` over every clip of ``clips``, in order."""
    loader = DataLoader(clips, batch_size=batch_size, num_workers=num_workers, shuffle=False)
    found = Discovered([], [], [])
    with Progress(disable=not progress) as bar:
        task = bar.add_task("discovering keyframes", total=len(clips))
        for batch in loader:
            found.predicted.extend(discoverer(batch["frames"], batch["future_length"]))
            found.truth.extend(keyframe_lists(batch["keyframes"]))
            found.lengths.extend(batch["future_length"].tolist())
            bar.update(task, advance=len(batch["frames"]))
    return found


def evaluate_discoverer(discoverer: Discoverer, clips: Dataset, n_future: int, **loader: Any) -> dict[str, float]:
    """:meth:`Discovered.scores` of ``discoverer`` on ``clips`` (``loader``: as :func:`discover`)."""
    return discover(discoverer, clips, **loader).scores(n_future)


PER_VIDEO_COLUMNS = ("clips", "precision", "recall", "f1", "f1_tol1", "hausdorff", "n_predicted", "n_true")


def save_video_scores(found: Discovered, videos: Sequence[str], n_future: int, folder: Path) -> Path:
    """``per_video.csv``: each video's precision, recall, F1 (its clips pooled), one row per video."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["video", *PER_VIDEO_COLUMNS])
    for video, scores in video_scores(found.predicted, found.truth, videos, n_future).items():
        scores = dict(scores, clips=scores["n_sequences"])
        writer.writerow([video, *(f"{scores[c]:.6g}" for c in PER_VIDEO_COLUMNS)])
    path = Path(folder) / "per_video.csv"
    atomic_write_text(path, out.getvalue())
    return path


def save_predictions(found: dict[str, Discovered], folder: Path) -> Path:
    """``predictions.json``: the true keyframes, valid future lengths and each method's keyframes
    (method → per clip) on every scored clip, in order.

    ``keyin-report`` draws its method-comparison figure from the first clips of these files;
    ``studies/recall_by_turn.py`` reads all of them.
    """
    first = next(iter(found.values()))
    record = {
        "clips": list(range(len(first.truth))),
        "truth": first.truth,
        "lengths": first.lengths,
        "predicted": {name: run.predicted for name, run in found.items()},
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
    tolerances: Sequence[int] = (1,),
    videos: Sequence[str] | None = None,
    **loader: Any,
) -> dict[str, Any]:
    """Score every discoverer, save pictures of the first and everyone's example predictions.

    Args:
        discoverers: method name → discoverer; the first is the method, the rest its variants.
        tolerances: the k of each ±k F1 (``f1_tol<k>``).
        videos: per clip, the video it was cut from: the first method's ``per_video.csv`` (None:
            each clip its own video).
        loader: ``batch_size``, ``num_workers``, ``progress`` for :func:`discover`.
    Returns:
        The first method's scores with ``method`` and, if there are more, ``variants``
        (name → scores).
    """
    found = {name: discover(find, clips, **loader) for name, find in discoverers.items()}
    scores = {name: run.scores(n_future, tolerances) for name, run in found.items()}
    (method, main), *others = scores.items()
    named = videos if videos is not None else [str(index) for index in range(len(clips))]
    save_video_scores(found[method], named, n_future, folder)
    save_examples(discoverers[method], clips, n_cond, folder)
    save_predictions(found, folder)
    metrics: dict[str, Any] = dict(main, method=method)
    if others:
        metrics["variants"] = dict(others)
    return metrics
