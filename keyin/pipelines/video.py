"""Video-prediction diagnostics of a stage-2 model (docs/evaluation.md, not in the paper's tables): the
model's predicted futures, scored by :mod:`keyin.eval.video`, and the pictures of them.

Each predicted future is the argmax-offset video (paper §3.1) of the posterior mean
(``mode="posterior"``, ``sample=False``: the reconstruction) or of a prior sample (``mode="prior"``,
``sample=True``: a prediction from the conditioning frames alone).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import torch
from rich.progress import Progress
from torch import Tensor
from torch.utils.data import DataLoader, Dataset

from keyin.decode.offsets import offset_keyframes
from keyin.eval.f1 import keyframe_lists
from keyin.eval.video import METRICS, clip_scores, sample_summary, summarize
from keyin.models import KEYIN
from keyin.viz.figures import save_labeled_strips
from keyin.viz.keyframes import marked_frames, save_keyframe_gif, save_keyframe_pictures


def device_of(model: KEYIN) -> torch.device:
    return next(model.parameters()).device


def predict(
    model: KEYIN, clips: Tensor, future_length: Tensor, mode: str, sample: bool
) -> tuple[Tensor, list[list[int]]]:
    """A KEYIN (or Jumpy, Static) model's argmax-offset video of each clip and its keyframe positions.

    Args:
        model: a trained :class:`keyin.models.KEYIN` in eval mode.
        clips: (B, L, C, H, W) in [0, 1]; the first n_cond frames condition the prediction.
        future_length: (B,).
        mode, sample: as in :meth:`keyin.models.KEYIN.forward`.
    Returns:
        (B, L, C, H, W) the conditioning frames then the predicted future; per clip the keyframe
        positions of the argmax offsets (future indices) inside the window, those the video shows.
    """
    clips = clips.to(device_of(model))
    out = model(clips, future_length.to(clips.device), mode=mode, sample=sample)
    window = torch.full_like(future_length, clips.shape[1] - model.n_cond)
    return model.argmax_video(clips, out), offset_keyframes(out["offset_probs"], window)


@dataclass
class Futures:
    """k predicted futures of B clips and how they score against the true futures.

    Attributes:
        videos: (k, B, L, C, H, W) the conditioning frames, then each prediction (:func:`predict`).
        keyframes: [k][B] each prediction's keyframe positions (future indices).
        scores: ``psnr`` and ``ssim``, each (k, B) (:func:`clip_scores`).
    """

    videos: Tensor
    keyframes: list[list[list[int]]]
    scores: dict[str, Tensor]

    def best(self) -> tuple[Tensor, list[list[int]], dict[str, Tensor]]:
        """Per clip the prediction of the highest PSNR (the first for a clip without valid frames):
        its video (B, L, C, H, W), keyframes [B] and ``psnr``/``ssim`` (B,)."""
        index = self.scores["psnr"].nan_to_num(-torch.inf).argmax(0)  # (B,)
        clips = torch.arange(len(index))
        keyframes = [self.keyframes[i][clip] for clip, i in enumerate(index.tolist())]
        return self.videos[index, clips], keyframes, {name: v[index, clips] for name, v in self.scores.items()}


def predict_futures(
    model: KEYIN, clips: Tensor, future_length: Tensor, k: int, mode: str = "prior", sample: bool = True
) -> Futures:
    """k predictions of each clip (:func:`predict`; k = 1 with ``sample=False`` for the posterior
    mean), scored against the clips' true futures over their valid frames.

    Args:
        clips: (B, L, C, H, W) in [0, 1]; future_length: (B,).
    """
    runs = [predict(model, clips, future_length, mode, sample) for _ in range(k)]
    videos = torch.stack([video for video, _ in runs])  # (k, B, L, C, H, W)
    n_cond = model.n_cond
    target = clips[:, n_cond:].to(videos.device)
    scores = [clip_scores(video[:, n_cond:], target, future_length) for video in videos]
    stacked = {name: torch.stack([score[name] for score in scores]) for name in METRICS}
    return Futures(videos, [keyframes for _, keyframes in runs], stacked)


def score_batch(model: KEYIN, clips: Tensor, future_length: Tensor, k: int) -> dict[str, Tensor]:
    """Per-clip scores of the posterior-mean reconstruction and of k prior samples.

    Args:
        clips: (B, L, C, H, W) in [0, 1].
        future_length: (B,).
    Returns:
        ``psnr``/``ssim`` (k, B) of the samples, ``psnr_posterior``/``ssim_posterior`` (B,), and
        ``psnr_blank``/``ssim_blank`` (B,): all-black frames, the reference a prediction must beat
        where the background is black (on Brownian a blurred or empty frame scores about as well).
    """
    posterior = predict_futures(model, clips, future_length, 1, "posterior", sample=False)
    samples = predict_futures(model, clips, future_length, k)
    future = clips[:, model.n_cond :].to(device_of(model))
    blank = clip_scores(torch.zeros_like(future), future, future_length.to(future.device))
    return {
        **samples.scores,
        **{f"{name}_posterior": posterior.scores[name][0] for name in METRICS},
        **{f"{name}_blank": blank[name] for name in METRICS},
    }


@torch.no_grad()
def evaluate_video(
    model: KEYIN,
    clips: Dataset,
    k: int,
    batch_size: int = 100,
    num_workers: int = 0,
    progress: bool = False,
) -> dict[str, float | int]:
    """``summarize`` over every clip of ``clips``, k prior samples per clip."""
    loader = DataLoader(clips, batch_size=batch_size, num_workers=num_workers, shuffle=False)
    batches = []
    with Progress(disable=not progress) as bar:
        task = bar.add_task(f"predicting videos ({k} samples)", total=len(clips))
        for batch in loader:
            batches.append(score_batch(model, batch["frames"], batch["future_length"], k))
            bar.update(task, advance=len(batch["frames"]))
    return summarize({name: torch.cat([scores[name] for scores in batches], dim=-1) for name in batches[0]})


def first_clips(clips: Dataset, count: int) -> dict[str, Tensor]:
    """The first ``count`` items of ``clips`` (all if fewer) as one batch."""
    return next(iter(DataLoader(clips, batch_size=min(count, len(clips)), shuffle=False)))


@torch.no_grad()
def save_rollouts(model: KEYIN, clips: Dataset, k: int, folder: Path, count: int = 4) -> tuple[Path, Path]:
    """``rollouts.png`` and ``rollouts.gif``: for each of the first ``count`` clips, the truth
    (true keyframes marked), the posterior-mean reconstruction (its keyframes marked, hits in
    yellow) and the one of k prior samples with the highest PSNR (its own keyframes marked).

    Returns:
        The PNG and GIF paths.
    """
    batch = first_clips(clips, count)
    frames, lengths = batch["frames"].to(device_of(model)), batch["future_length"]
    posterior = predict_futures(model, frames, lengths, 1, "posterior", sample=False)
    best_video, best_keyframes, _ = predict_futures(model, frames, lengths, k).best()
    truth = keyframe_lists(batch["keyframes"])
    rows = torch.stack([frames, posterior.videos[0], best_video], dim=1).flatten(0, 1).cpu()  # (3·count, L, C, H, W)
    clips_truth = [marks for clip in truth for marks in (clip, clip, [])]
    clips_predicted = [
        marks for clip in range(len(truth)) for marks in ([], posterior.keyframes[0][clip], best_keyframes[clip])
    ]
    return save_keyframe_pictures(
        folder, rows, model.n_cond, clips_truth, clips_predicted, name="rollouts", per_column=3
    )


@torch.no_grad()
def save_prior_samples(
    model: KEYIN, clips: Dataset, k: int, folder: Path, count: int = 4, name: str = "samples"
) -> dict[str, Any]:
    """``<name>.png`` and ``<name>.gif`` (the paper's Fig. 5 and 10): for each of the first ``count``
    clips the truth (its true keyframes in green), then k futures drawn from the prior given its
    conditioning frames, each with its own keyframes in red; the PNG labels each sample's PSNR.

    Returns:
        ``clips``: per pictured clip its index, ``true_keyframes`` and ``samples`` (each sample's
        ``keyframes``, ``psnr``, ``ssim``); :func:`sample_summary` of the pictured samples; ``k``.
    """
    batch = first_clips(clips, count)
    frames, lengths = batch["frames"].to(device_of(model)), batch["future_length"]
    samples = predict_futures(model, frames, lengths, k)
    rows, labels, pictured = [], [], []
    for clip, truth in enumerate(keyframe_lists(batch["keyframes"])):
        rows.append(marked_frames(frames[clip], model.n_cond, truth, []))
        labels.append(f"clip {clip}\nground truth")
        drawn = []
        for index, video in enumerate(samples.videos[:, clip]):
            keyframes = samples.keyframes[index][clip]
            scores = {metric: float(samples.scores[metric][index, clip]) for metric in METRICS}
            rows.append(marked_frames(video, model.n_cond, [], keyframes))
            labels.append(f"sample {index + 1}\nPSNR {scores['psnr']:.1f}")
            drawn.append({"keyframes": keyframes, **scores})
        pictured.append({"clip": clip, "true_keyframes": truth, "samples": drawn})
    save_labeled_strips(rows, labels, Path(folder) / f"{name}.png")
    save_keyframe_gif(Path(folder) / f"{name}.gif", np.stack(rows), per_column=k + 1)
    return {"clips": pictured, **sample_summary(samples.scores), "k": k}
