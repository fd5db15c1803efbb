"""Video-prediction diagnostics of a stage-2 model (REFERENCE §5.4, not in the paper's tables).

Each predicted future is the argmax-offset video (REFERENCE §3.9) of the posterior mean
(``mode="posterior"``, ``sample=False``: the reconstruction) or of a prior sample (``mode="prior"``,
``sample=True``: a prediction from the conditioning frames alone). PSNR and SSIM are computed per
frame against the true future, averaged over each clip's valid frames (padding never counts), then:
``best_of_k`` = per clip the best of the k samples, averaged over clips (the best sample for PSNR
and the one for SSIM may differ); ``mean`` = averaged over samples and clips.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping, Protocol

import torch
from rich.progress import Progress
from torch import Tensor
from torch.utils.data import DataLoader, Dataset
from torchmetrics.functional.image import peak_signal_noise_ratio, structural_similarity_index_measure

from keyin.eval.f1 import keyframe_lists
from keyin.losses.soft_keyframe import argmax_positions, valid_frame_mask
from keyin.viz.keyframes import save_keyframe_pictures

PSNR_CAP = 100.0
"""dB, the PSNR of an exact match (MSE 0 gives +inf): means and the best of k stay finite."""
METRICS = ("psnr", "ssim")


class KeyframeVideoModel(Protocol):
    """What the diagnostics use of a stage-2 model (``keyin.lit.keyframes.KeyframeModule``)."""

    @property
    def device(self) -> torch.device:
        """Where its weights are."""
        ...

    @property
    def hparams(self) -> Mapping[str, Any]:
        """Its settings; ``hparams["stage1"]["n_cond"]`` is the number of conditioning frames."""
        ...

    def __call__(self, clips: Tensor, future_length: Tensor, mode: str, sample: bool) -> dict[str, Tensor]:
        """(B, L, C, H, W) clips, (B,) valid future lengths -> its outputs, ``offset_probs`` (B, M, S) among them."""
        ...

    def argmax_video(self, clips: Tensor, out: dict[str, Tensor]) -> Tensor:
        """(B, L, C, H, W): the conditioning frames of ``clips``, then the argmax-offset future of ``out``."""
        ...

    def discover(self, clips: Tensor, future_length: Tensor, discovery: str) -> list[list[int]]:
        """Per clip, its keyframes' future indices under the decoding rule ``discovery``."""
        ...


def frame_scores(predicted: Tensor, target: Tensor) -> dict[str, Tensor]:
    """PSNR (capped at ``PSNR_CAP``) and SSIM of each frame pair, frames in [0, 1].

    Args:
        predicted, target: (F, C, H, W).
    Returns:
        ``psnr`` and ``ssim``, each (F,): one value per frame, nothing pooled across frames.
    """
    psnr = peak_signal_noise_ratio(predicted, target, data_range=1.0, reduction="none", dim=(1, 2, 3))
    ssim = structural_similarity_index_measure(predicted, target, data_range=1.0, reduction="none")
    return {"psnr": psnr.clamp(max=PSNR_CAP), "ssim": ssim}


def clip_scores(predicted: Tensor, target: Tensor, future_length: Tensor) -> dict[str, Tensor]:
    """Mean PSNR and SSIM over each clip's valid future frames (REFERENCE §3.8).

    Args:
        predicted, target: (B, N, C, H, W) future frames in [0, 1].
        future_length: (B,) valid future frames; the frames past them are ignored.
    Returns:
        ``psnr`` and ``ssim``, each (B,); NaN for a clip without valid frames.
    """
    valid = valid_frame_mask(future_length.to(target.device), target.shape[1])  # (B, N)
    per_frame = frame_scores(predicted.flatten(0, 1), target.flatten(0, 1))
    return {
        name: torch.where(valid, values.view(valid.shape), 0.0).sum(1) / valid.sum(1)
        for name, values in per_frame.items()
    }


def predict(
    module: KeyframeVideoModel, clips: Tensor, future_length: Tensor, mode: str, sample: bool
) -> tuple[Tensor, Tensor]:
    """A stage-2 module's argmax-offset video of each clip and its keyframe positions.

    Args:
        module: a stage-2 model in eval mode.
        clips: (B, L, C, H, W) in [0, 1]; the first n_cond frames condition the prediction.
        future_length: (B,).
        mode, sample: "posterior" or "prior", and whether to sample the latents or take their means.
    Returns:
        (B, L, C, H, W) the conditioning frames then the predicted future; (B, M) keyframe
        positions (future indices).
    """
    clips = clips.to(module.device)
    out = module(clips, future_length.to(module.device), mode=mode, sample=sample)
    return module.argmax_video(clips, out), argmax_positions(out["offset_probs"])


def score_batch(module: KeyframeVideoModel, clips: Tensor, future_length: Tensor, k: int) -> dict[str, Tensor]:
    """Per-clip scores of the posterior-mean reconstruction and of k prior samples.

    Args:
        clips: (B, L, C, H, W) in [0, 1].
        future_length: (B,).
    Returns:
        ``psnr``/``ssim`` (k, B) of the samples and ``psnr_posterior``/``ssim_posterior`` (B,).
    """
    n_cond = module.hparams["stage1"]["n_cond"]
    target = clips[:, n_cond:].to(module.device)

    def scores(mode: str, sample: bool) -> dict[str, Tensor]:
        video, _ = predict(module, clips, future_length, mode, sample)
        return clip_scores(video[:, n_cond:], target, future_length)

    posterior = scores("posterior", False)
    samples = [scores("prior", True) for _ in range(k)]
    return {
        **{name: torch.stack([sample[name] for sample in samples]) for name in METRICS},
        **{f"{name}_posterior": posterior[name] for name in METRICS},
    }


def summarize(scores: dict[str, Tensor]) -> dict[str, float | int]:
    """Means over clips (those without valid frames left out) of the ``score_batch`` scores.

    Returns:
        ``<metric>_best_of_k`` (per clip the max over samples), ``<metric>_mean``,
        ``<metric>_posterior`` for PSNR and SSIM, and ``k``.
    """
    summary: dict[str, float | int] = {}
    for name in METRICS:
        samples = scores[name]  # (k, B)
        summary[f"{name}_best_of_k"] = float(samples.max(0).values.nanmean())
        summary[f"{name}_mean"] = float(samples.nanmean())
        summary[f"{name}_posterior"] = float(scores[f"{name}_posterior"].nanmean())
    summary["k"] = scores["psnr"].shape[0]
    return summary


@torch.no_grad()
def evaluate_video(
    module: KeyframeVideoModel,
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
            batches.append(score_batch(module, batch["frames"], batch["future_length"], k))
            bar.update(task, advance=len(batch["frames"]))
    return summarize({name: torch.cat([scores[name] for scores in batches], dim=-1) for name in batches[0]})


@torch.no_grad()
def save_rollouts(
    module: KeyframeVideoModel, clips: Dataset, k: int, folder: Path, count: int = 4
) -> tuple[Path, Path]:
    """``rollouts.png`` and ``rollouts.gif``: for each of the first ``count`` clips, the truth
    (true keyframes marked), the posterior-mean reconstruction (its keyframes marked, hits in
    yellow) and the one of k prior samples with the highest PSNR (its own keyframes marked).

    Returns:
        The PNG and GIF paths.
    """
    batch = next(iter(DataLoader(clips, batch_size=min(count, len(clips)), shuffle=False)))
    frames, lengths = batch["frames"].to(module.device), batch["future_length"]
    n_cond = module.hparams["stage1"]["n_cond"]
    posterior, _ = predict(module, frames, lengths, "posterior", False)
    samples = [predict(module, frames, lengths, "prior", True) for _ in range(k)]
    psnr = torch.stack(
        [clip_scores(video[:, n_cond:], frames[:, n_cond:], lengths)["psnr"] for video, _ in samples]
    )  # (k, B)
    best = psnr.nan_to_num(-torch.inf).argmax(0).tolist()  # per clip; without valid frames the first
    best_video = torch.stack([samples[index][0][clip] for clip, index in enumerate(best)])
    best_positions = [samples[index][1][clip].tolist() for clip, index in enumerate(best)]
    truth = keyframe_lists(batch["keyframes"])
    discovered = module.discover(frames, lengths, discovery="offsets")
    rows = torch.stack([frames, posterior, best_video], dim=1).flatten(0, 1).cpu()  # (3·count, L, C, H, W)
    clips_truth = [marks for clip in range(len(best)) for marks in (truth[clip], truth[clip], [])]
    clips_predicted = [
        marks for clip in range(len(best)) for marks in ([], discovered[clip], best_positions[clip])
    ]
    return save_keyframe_pictures(
        folder, rows, n_cond, clips_truth, clips_predicted, name="rollouts", per_column=3
    )
