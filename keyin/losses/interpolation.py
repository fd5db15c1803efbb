"""Stage 1's training terms (paper §3.2 "Training procedure", §4): the image likelihood of interpolated segments
and of auto-encoded frames, and the per-offset contrast that gates stage 2.

The decoder is passed in as a callable ((R, E) embeddings → (R, C, H, W) logits), so these stay
functions of tensors; ``keyin.lit.interpolator`` composes them, and the exact segmentation's segment
costs (``keyin.decode.segment_costs``) are :func:`interpolation_bce` of every segment.
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
    decoder: Decoder, predicted: Tensor, valid: Tensor, frames: Tensor, weights: Tensor | None, clip: Tensor,
    positions: Tensor,
) -> Tensor:
    """Summed (pixel-weighted) BCE of each segment's interpolated frames against the true ones.

    Args:
        predicted: (R, S, E) interpolated embeddings; valid: (R, S) which of them exist.
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
    logits = decoder(predicted[valid]).float().reshape(targets.shape)
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
    predicted, valid, stats = interpolate_segments(interpolator, posterior, embeddings, *segments, latent)
    clip, start, offset = (index.to(embeddings.device) for index in segments)
    positions, _ = segment_frames(start, offset, interpolator.max_offset)
    bce = segment_bce(decoder, predicted, valid, frames, weights, clip, positions - first_frame)
    return bce, valid.sum(1), stats


def autoencoding_bce(
    decoder: Decoder, frames: Tensor, embeddings: Tensor, weights: Tensor | None,
    subset: int = 0, generator: torch.Generator | None = None,
) -> Tensor:
    """Summed (pixel-weighted) BCE of decoding the frames' own embeddings.

    Args:
        frames: (F, C, H, W); embeddings: (F, E); weights: like ``frames`` or None.
        subset: > 0 decodes a uniform random subset of that many frames (drawn with ``generator``)
            and rescales the sum to all F, an unbiased estimate at a fraction of the decoder's cost.
    Returns:
        () the sum over pixels and frames.
    """
    n_frames = frames.shape[0]
    if 0 < subset < n_frames:
        pick = torch.randperm(n_frames, generator=generator)[:subset].to(frames.device)
        frames, embeddings = frames[pick], embeddings[pick]
        weights = None if weights is None else weights[pick]
    logits = decoder(embeddings).float()
    bce = F.binary_cross_entropy_with_logits(logits, frames.to(logits), None if weights is None else weights.to(logits),
                                             reduction="sum")
    return bce * n_frames / frames.shape[0]


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
