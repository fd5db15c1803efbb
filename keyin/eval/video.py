"""Video-prediction scores (docs/evaluation.md, not in the paper's tables): PSNR and SSIM of predicted
futures against the true ones, per frame, averaged over each clip's valid frames (padding never
counts), then summarised over samples: ``best_of_k`` = per clip the best of the k samples, averaged
over clips (the best sample for PSNR and the one for SSIM may differ); ``mean`` = averaged over
samples and clips. The predictions themselves are made by :mod:`keyin.pipelines.video`.
"""

from __future__ import annotations

import torch
from torch import Tensor
from torchmetrics.functional.image import peak_signal_noise_ratio, structural_similarity_index_measure

from keyin.models.positions import valid_frame_mask

PSNR_CAP = 100.0
"""dB, the PSNR of an exact match (MSE 0 gives +inf): means and the best of k stay finite."""
METRICS = ("psnr", "ssim")


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
    """Mean PSNR and SSIM over each clip's valid future frames (docs/architecture.md, "Padding and masking").

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


def sample_summary(scores: dict[str, Tensor]) -> dict[str, float]:
    """``<metric>_best_of_k`` (per clip the max over samples, averaged over clips) and
    ``<metric>_mean`` of (k, B) sample scores, clips without valid frames left out."""
    summary = {}
    for name in METRICS:
        samples = scores[name]  # (k, B)
        summary[f"{name}_best_of_k"] = float(samples.max(0).values.nanmean())
        summary[f"{name}_mean"] = float(samples.nanmean())
    return summary


def summarize(scores: dict[str, Tensor]) -> dict[str, float | int]:
    """Means over clips (those without valid frames left out) of the ``score_batch`` scores.

    Returns:
        ``<metric>_best_of_k`` (per clip the max over samples), ``<metric>_mean``,
        ``<metric>_posterior``, ``<metric>_blank`` for PSNR and SSIM, and ``k``.
    """
    summary: dict[str, float | int] = sample_summary(scores)
    for name in METRICS:
        for kind in ("posterior", "blank"):
            summary[f"{name}_{kind}"] = float(scores[f"{name}_{kind}"].nanmean())
    summary["k"] = scores["psnr"].shape[0]
    return summary
