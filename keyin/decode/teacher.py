"""The segmentation teacher's targets (our addition, docs/decisions.md): the exact best segmentation
of each clip under KEYIN's own frozen interpolator, turned into offsets and per-frame boundaries.

No ground-truth keyframe enters: the segmentation minimises the interpolation error between the
clip's true frames in embedding space (the decoder-free, cheap segment cost). The losses that use
the targets are :func:`keyin.losses.soft_keyframe.offset_teacher_loss` and
:func:`keyin.losses.soft_keyframe.boundary_teacher_loss`.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor

from keyin.decode.segment_costs import embedding_costs
from keyin.decode.segmentation import KeyframeCost, decode_by_length, segmentation_offsets
from keyin.losses.soft_keyframe import boundary_teacher_loss, offset_teacher_loss
from keyin.models.keyin import KEYIN


@dataclass(frozen=True)
class TeacherConfig:
    """The segmentation teacher of stage 2 (ours, off at ``weight`` 0): its loss weight, the clips per
    step it scores (0: all), its price per keyframe (nats, or "knee"), teacher forcing of the previous
    keyframe (``chain``) and whether it also says where the chain leaves the clip (``leaves``)."""

    weight: float = 0.0
    clips: int = 0
    keyframe_cost: KeyframeCost = 0.0
    chain: bool = False
    leaves: bool = False


@torch.no_grad()
def segmentation_targets(
    interpolator: torch.nn.Module, boundary_emb: Tensor, lengths: Tensor, n_keyframes: int,
    keyframe_cost: KeyframeCost = 0.0, leave: bool = False,
) -> tuple[Tensor, Tensor]:
    """Teacher offsets and boundary labels of clips, each segmented within its own valid frames.

    Args:
        interpolator: the frozen :class:`keyin.models.Interpolator`, run with z = 0.
        boundary_emb: (B, N + 1, E) embeddings on the extended index (K^0, then the future frames).
        lengths: (B,) valid future frames.
        n_keyframes: M.
        keyframe_cost: price per keyframe in the DP (0: every gap it may; "knee": each clip's knee count).
        leave: teach the keyframe after the last interior one to leave the clip (``segmentation_offsets``).
    Returns:
        offsets (B, M) int64 (:func:`keyin.decode.segmentation.segmentation_offsets`) and
        boundaries (B, N) float, 1 at the interior keyframes; both on ``boundary_emb``'s device.
    """
    n_future = boundary_emb.shape[1] - 1
    positions = decode_by_length(
        lambda rows, length: embedding_costs(interpolator, boundary_emb[rows.to(boundary_emb.device), : length + 1]),
        lengths.cpu(), n_keyframes, interpolator.max_offset, keyframe_cost,
    )
    boundaries = torch.zeros(len(positions), n_future)
    for row, clip_positions in enumerate(positions):
        boundaries[row, clip_positions] = 1.0
    offsets = segmentation_offsets(positions, lengths.tolist(), n_keyframes, interpolator.max_offset, leave)
    return offsets.to(boundary_emb.device), boundaries.to(boundary_emb.device)


def teacher_loss(
    model: KEYIN, clips: Tensor, out: dict[str, Tensor | None], future_length: Tensor,
    keyframe_cost: KeyframeCost = 0.0, n_clips: int = 0, chained: bool = False, leave: bool = False,
) -> Tensor:
    """Cross-entropy of δ (and, where the model has boundary scores, of those) to the
    :func:`segmentation_targets` of the first ``n_clips`` clips (0: all).

    Args:
        model: the KEYIN model whose frozen interpolator segments the clips.
        clips: (B, L, C, H, W) the clips of ``out``.
        out: a :meth:`keyin.models.KEYIN.forward` of the clips (``boundary_emb``, ``offset_logits``,
            ``boundary_scores``).
        future_length: (B,) valid future frames.
        chained: teacher forcing: δ's offset evidence places each previous keyframe at the
            teacher's position (the model run again on those clips with ``chain`` = the teacher's
            offsets), as the argmax readout places it at its own; False: δ as in ``out``.
    Returns:
        () the loss.
    """
    n_clips = n_clips or out["boundary_emb"].shape[0]
    lengths = future_length[:n_clips]
    offsets, boundaries = segmentation_targets(
        model.interpolator, out["boundary_emb"][:n_clips].detach(), lengths, model.predictor.n_keyframes, keyframe_cost,
        leave,
    )
    logits = out["offset_logits"][:n_clips]
    if chained:
        logits = model.keyframes(clips[:n_clips], lengths, chain=offsets)[1].offset_logits
    loss = offset_teacher_loss(logits, offsets)
    if out["boundary_scores"] is not None:
        loss = loss + boundary_teacher_loss(out["boundary_scores"][:n_clips], boundaries, lengths)
    return loss
