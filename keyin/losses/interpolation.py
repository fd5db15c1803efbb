"""Stage 1's training terms (paper §3.2 "Training procedure", §4): the image likelihood of interpolated segments
and of auto-encoded frames, and the per-offset contrast that gates stage 2.

The terms score logits, and :func:`interpolation_bce` takes the decoder as a callable ((R, E) embeddings → (R, C, H, W)
logits), so these stay functions of tensors; ``keyin.lit.interpolator`` composes them (its training step decodes both
terms' frames in one batch), and the exact segmentation's segment costs (``keyin.decode.segment_costs``) are
:func:`interpolation_bce` of every segment.
"""

from __future__ import annotations

from typing import Callable

import torch
import torch.nn.functional as F
from torch import Tensor

from keyin.data.segments import all_segments, crosses_keyframe, segment_frames
from keyin.models.interpolator import Interpolator, InterpolatorPosterior, interpolate_segments

Decoder = Callable[[Tensor], Tensor]
# (clip, start, offset), each (R,) -> per-segment summed BCE (R,) and its frame count (R,)
SegmentScorer = Callable[[Tensor, Tensor, Tensor], tuple[Tensor, Tensor]]


def segment_bce(
    logits: Tensor, valid: Tensor, frames: Tensor, weights: Tensor | None, clip: Tensor, positions: Tensor
) -> Tensor:
    """Summed (pixel-weighted) BCE of each segment's interpolated frames against the true ones.

    Args:
        logits: (V, C, H, W) or (V, D) the decoded interpolated frames that exist, ``decoder(predicted[valid])``.
        valid: (R, S) which of each segment's S outputs exist.
        frames: (B, L, ...) targets in [0, 1], images (C, H, W) or flattened (D); weights: like
            ``frames`` or None (plain BCE).
        clip: (R,) each segment's clip; positions: (R, S) where each output's frame lies on ``frames``' axis L.
    Returns:
        (R,) float32 sums, whatever the precision of the networks.
    """
    rows = clip[:, None].expand_as(positions)[valid]
    positions = positions[valid]
    targets = frames[rows, positions]  # (V, ...)
    weights = None if weights is None else weights[rows, positions]
    logits = logits.float().reshape(targets.shape)
    bce = F.binary_cross_entropy_with_logits(logits, targets.to(logits), None if weights is None else weights.to(logits),
                                             reduction="none")
    return logits.new_zeros(valid.shape[0]).index_put_((valid.nonzero()[:, 0],), bce.flatten(1).sum(1), accumulate=True)


def interpolation_bce(
    interpolator: Interpolator, posterior: InterpolatorPosterior | None, decoder: Decoder, embeddings: Tensor,
    frames: Tensor, weights: Tensor | None, segments: tuple[Tensor, Tensor, Tensor], latent: str, first_frame: int = 0,
) -> tuple[Tensor, Tensor, tuple[Tensor, Tensor] | None]:
    """Interpolate segments between their boundary embeddings and score the frames they render: stage 1's
    image term, and the exact segmentation's segment cost (``keyin.decode.segment_costs``).

    Args:
        embeddings: (B, L, E) encoded clips.
        frames: (B, L - first_frame, ...) the clips' frames from index ``first_frame`` on (see
            :func:`segment_bce`); weights: like ``frames`` or None.
        segments: clip, start, offset (R,) on the embeddings' axis (:mod:`keyin.data.segments`).
        latent: "posterior", "prior" or "mean" (:func:`keyin.models.interpolator.interpolate_segments`).
        first_frame: 1 where ``frames`` leave out the clips' first frame (K^0), which no segment renders.
    Returns:
        per-segment BCE (R,), frames per segment (R,), and the posterior's (mu, log_sigma), each
        (R, Zi), where z was drawn from it (else None).
    """
    predicted, valid, positions, stats = interpolated_outputs(interpolator, posterior, embeddings, segments, latent)
    bce = segment_bce(decoder(predicted[valid]), valid, frames, weights, segments[0].to(valid.device), positions - first_frame)
    return bce, valid.sum(1), stats


def interpolated_outputs(
    interpolator: Interpolator, posterior: InterpolatorPosterior | None, embeddings: Tensor,
    segments: tuple[Tensor, Tensor, Tensor], latent: str,
) -> tuple[Tensor, Tensor, Tensor, tuple[Tensor, Tensor] | None]:
    """The interpolated embeddings of ``segments`` (clip, start, offset, each (R,)) and where their frames lie.

    Returns:
        predicted (R, S, E), valid (R, S), positions (R, S) on the clip axis, and the posterior's (mu, log_sigma)
        where z was drawn from it (else None) (:func:`keyin.models.interpolator.interpolate_segments`).
    """
    predicted, valid, stats = interpolate_segments(interpolator, posterior, embeddings, *segments, latent)
    _, start, offset = (index.to(embeddings.device) for index in segments)
    positions, _ = segment_frames(start, offset, interpolator.max_offset)
    return predicted, valid, positions, stats


def autoencoding_pick(n_frames: int, subset: int = 0, generator: torch.Generator | None = None) -> Tensor | None:
    """Which of ``n_frames`` frames the auto-encoding term decodes: a uniform random ``subset`` of them (drawn with
    ``generator``), or None for all (``subset`` 0 or ≥ ``n_frames``); :func:`autoencoding_bce` rescales to all."""
    return torch.randperm(n_frames, generator=generator)[:subset] if 0 < subset < n_frames else None


def autoencoding_bce(logits: Tensor, frames: Tensor, weights: Tensor | None, n_frames: int | None = None) -> Tensor:
    """Summed (pixel-weighted) BCE of the frames decoded from their own embeddings.

    Args:
        logits: (F', C, H, W) ``decoder(embeddings)``; frames: (F', C, H, W) in [0, 1]; weights: like ``frames`` or None.
        n_frames: the frames F' was drawn from (:func:`autoencoding_pick`): the sum is rescaled to all of them, an
            unbiased estimate at a fraction of the decoder's cost. None: F'.
    Returns:
        () the sum over pixels and frames.
    """
    logits = logits.float()
    bce = F.binary_cross_entropy_with_logits(logits, frames.to(logits), None if weights is None else weights.to(logits),
                                             reduction="sum")
    return bce if n_frames is None else bce * n_frames / frames.shape[0]


def offset_contrast(
    score: SegmentScorer, keyframes: Tensor, last: Tensor, first: int, max_offset: int
) -> dict[int, dict[str, float]]:
    """Mean BCE per frame of segments with ("bent") and without ("straight") a labelled keyframe
    strictly inside, per offset: the gate before stage 2 (PROTOTYPE-FINDINGS §4).

    Args:
        score: BCE and frame count of segments (:data:`SegmentScorer`).
        keyframes: (B, L) bool labels on the clip axis.
        last: (B,) each clip's last valid frame; segments reaching past it are left out.
        first: the first frame a segment may start at (K^0, the last conditioning frame).
    Returns:
        ``{offset: {"straight": mean, "bent": mean, "all": mean}}`` for offsets 1..S (NaN where none).
    """
    table = {}
    for offset in range(1, max_offset + 1):
        clip, start, offs = all_segments(len(keyframes), first, keyframes.shape[1] - 1, range(offset, offset + 1))
        inside = start + offs <= last[clip]
        clip, start, offs = clip[inside], start[inside], offs[inside]
        bce, count = score(clip, start, offs)
        per_frame = bce / count
        bent = crosses_keyframe(keyframes.cpu(), clip, start, offs).to(bce.device)
        table[offset] = {
            "straight": per_frame[~bent].mean().item() if (~bent).any() else float("nan"),
            "bent": per_frame[bent].mean().item() if bent.any() else float("nan"),
            "all": per_frame.mean().item() if len(per_frame) else float("nan"),
        }
    return table
