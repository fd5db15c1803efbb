"""Per-pixel weights of the image likelihood: moving objects count more (docs/decisions.md).

On the pushing frames the puck and the pusher cover ~17 of 4096 pixels and their colours sit in
the middle of [0, 1], where the pixel BCE is flat: a frame without them costs < 80 of ~5500 nats, so
the decoder learns them last and stage 1 cannot tell pushes apart (docs/pushing_models.md). The
weight ``w`` multiplies the BCE of every pixel of a frame that differs from the clip's first frame
(``max_c |I_t - I_0| > threshold``): where the objects are now and where they were. ``w = 1`` is the
plain BCE of the paper, and the function then returns None so callers skip the product.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import torch
from torch import Tensor

if TYPE_CHECKING:
    from keyin.models.config import FrameModelConfig


def changed_pixel_weights(clips: Tensor, weight: float, threshold: float) -> Tensor | None:
    """Weights of every pixel of every frame, the same for all channels.

    Args:
        clips: (B, L, C, H, W) frames in [0, 1]; frame 0 is the reference.
        weight: the weight of a changed pixel; unchanged ones weigh 1.
        threshold: least absolute change, in any channel, that marks a pixel as changed.
    Returns:
        (B, L, C, H, W) weights, or None when ``weight == 1``.
    """
    if weight <= 0:
        raise ValueError(f"foreground_weight must be > 0 (1 = plain BCE), got {weight}")
    if weight == 1:
        return None
    changed = (clips - clips[:, :1]).abs().amax(2, keepdim=True) > threshold  # (B, L, 1, H, W)
    weights = torch.where(changed, weight, 1.0).to(clips.dtype)
    return weights.expand_as(clips)


def frame_pixel_weights(clips: Tensor, frames: FrameModelConfig) -> Tensor | None:
    """:func:`changed_pixel_weights` of (B, L, C, H, W) clips at a frame model's ``foreground_weight``
    and ``foreground_threshold``: the weights stage 1 was trained with, (B, L, C, H, W) or None."""
    return changed_pixel_weights(clips, frames.foreground_weight, frames.foreground_threshold)


def future_pixel_weights(weights: Tensor | None, n_cond: int) -> Tensor | None:
    """(B, N, C·H·W) weights of the future frames, the layout of the soft loss and the segment costs."""
    return None if weights is None else weights[:, n_cond:].flatten(2)


def model_pixel_weights(clips: Tensor, hparams: Mapping[str, Any]) -> Tensor | None:
    """:func:`changed_pixel_weights` with a model's hyper-parameters; checkpoints from
    before the weighting have none and get the plain BCE."""
    return changed_pixel_weights(
        clips, hparams.get("foreground_weight", 1.0), hparams.get("foreground_threshold", 0.1)
    )


def plain_bce(hparams: Mapping[str, Any]) -> bool:
    """Whether a model's image likelihood is the plain BCE (:func:`model_pixel_weights` gives None)."""
    return hparams.get("foreground_weight", 1.0) == 1
