"""The Surprise baseline's loss (SVG-FP, paper App. 9): per-step prediction BCE and KL to the fixed
prior N(0, I), an optional auto-encoding BCE, and the KL weight's schedule.

Clips have L frames, the first ``n_cond`` conditioning; step t predicts frame t from frame t - 1, so
the per-step terms cover frames 1 … L-1. Padding (frames past ``n_cond + future_length``) adds nothing.
"""

from __future__ import annotations

from typing import NamedTuple

import torch
import torch.nn.functional as F
from torch import Tensor

from keyin.models.distributions import gaussian_kl


class SVGTerms(NamedTuple):
    """The loss terms of a batch of B clips of L frames.

    Attributes:
        bce: (B, L-1) prediction BCE of frames 1 … L-1, summed over pixels, zero on padding.
        kl: (B, L-1) KL of the posterior of steps 1 … L-1, zero on padding.
        valid: (B, L-1) bool, the valid frames among 1 … L-1.
        autoencoding: () summed BCE of the valid frames decoded from their own embeddings (0 without).
    """

    bce: Tensor
    kl: Tensor
    valid: Tensor
    autoencoding: Tensor


def kl_schedule(step: int, beta: float, warmup: int, delay: int) -> float:
    """KL weight at ``step``: 0 for ``delay`` steps, then rising linearly to ``beta`` over ``warmup``."""
    if step < delay:
        return 0.0
    return beta * (min(1.0, (step - delay) / warmup) if warmup > 0 else 1.0)


def svg_terms(
    logits: Tensor,
    mu: Tensor,
    log_sigma: Tensor,
    reconstruction: Tensor | None,
    clips: Tensor,
    valid: Tensor,
    weights: Tensor | None = None,
) -> SVGTerms:
    """The per-step terms of one teacher-forced pass (:class:`keyin.models.svg.SVGOutput`).

    Args:
        logits: (B, L-1, C, H, W) predictions of frames 1 … L-1.
        mu, log_sigma: (B, L, Z) the posterior of every step.
        reconstruction: (B, L, C, H, W) auto-encoded logits, or None for no auto-encoding term.
        clips: (B, L, C, H, W) targets in [0, 1].
        valid: (B, L) bool (:func:`keyin.data.segments.valid_frames`).
        weights: (B, L, C, H, W) pixel weights of the targets (keyin/losses/image.py), or None.
    """
    bce = F.binary_cross_entropy_with_logits(
        logits, clips[:, 1:], None if weights is None else weights[:, 1:], reduction="none"
    ).flatten(2).sum(-1)
    kl = gaussian_kl(mu[:, 1:], log_sigma[:, 1:])
    autoencoding = clips.new_zeros(())
    if reconstruction is not None:
        autoencoding = F.binary_cross_entropy_with_logits(
            reconstruction[valid], clips[valid], None if weights is None else weights[valid], reduction="sum"
        )
    future = valid[:, 1:]
    return SVGTerms(bce * future, kl * future, future, autoencoding)


def svg_loss(terms: SVGTerms, beta: float, ae_weight: float) -> Tensor:
    """() the batch's loss per clip: BCE + ``beta`` · KL + ``ae_weight`` · auto-encoding BCE."""
    return (terms.bce.sum() + beta * terms.kl.sum() + ae_weight * terms.autoencoding) / terms.bce.shape[0]


def kl_reveal_ratio(kl: Tensor, valid: Tensor, keyframes: Tensor, n_cond: int) -> Tensor:
    """Is the KL where the turns are? The mean KL at the frames after a labelled vertex over that
    elsewhere, on the valid future steps.

    Args:
        kl, valid: (B, L-1) of :class:`SVGTerms`.
        keyframes: (B, N) bool labels of the future frames, N = L - n_cond.
    Returns:
        () the ratio.
    """
    reveals = F.pad(keyframes, (n_cond, 0))[:, :-1].bool()  # (B, L-1): step t+1 after vertex t
    future_kl = kl.masked_fill(~valid, float("nan"))
    future_kl[:, : n_cond - 1] = float("nan")  # the conditioning frames have no labels
    return future_kl[reveals].nanmean() / future_kl[~reveals].nanmean().clamp_min(1e-9)
