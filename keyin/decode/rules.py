"""The math under KEYIN's rules (:mod:`keyin.decode.registry`) on the exact segmentation — ``boundaries``,
``map`` — what every rule reads of a model (:func:`read_posterior`), and the stage-1 gate.

KEYIN's stage 2 can only find keyframes that make the frozen interpolator's job easier. Given the
true frames, the best it could possibly do is the hard segmentation that minimises the summed
interpolation BCE; its F1 against the ground truth measures whether an interpolator is good enough
for stage 2 to discover the ground truth, before stage 2 is trained (PROTOTYPE-FINDINGS §4).
Every rule returns, per clip, keyframe positions inside the clip's valid frames.
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor

from keyin.decode.ends import sequence_ends, with_ends
from keyin.decode.offsets import keyframe_probabilities
from keyin.decode.segment_costs import boundary_segment_costs, candidate_segments, interpolation_costs
from keyin.decode.segmentation import KeyframeCost, decode_by_length
from keyin.losses.image import future_pixel_weights
from keyin.models.keyin import KEYIN
from keyin.models.keyframe_predictor import KeyframeOutput

def boundary_keyframes(scores: Tensor, lengths: Tensor, n_keyframes: int, max_offset: int) -> list[list[int]]:
    """The most likely keyframe positions under per-frame boundary scores, at most M gaps of at most S.

    Args:
        scores: (B, N) boundary logits; lengths: (B,) valid future frames.
    Returns:
        Per clip, the interior keyframe positions (the clip's last frame is never one).
    """
    return decode_by_length(
        lambda rows, length: boundary_segment_costs(scores[rows, :length].detach().float(), max_offset),
        lengths, n_keyframes, max_offset,
    )


def with_sequence_ends(positions: list[list[int]], lengths: Tensor, n_future: int) -> list[list[int]]:
    """Add the last valid frame of every clip that ends inside the window as a keyframe.

    A segmentation closes each clip at its last valid frame. Where the sequence ends before N
    (a demonstration that finished: the rest is padding) that closing boundary is the end of the
    last subgoal, a keyframe of the data; where the clip fills the window, the window cut the
    sequence and its last frame is no event. Full-length datasets (Brownian) are unchanged.

    Args:
        positions: per clip, interior keyframe positions; lengths: (B,) valid future frames.
    Returns:
        Per clip, the positions with ``length - 1`` added for clips with ``0 < length < n_future``.
    """
    return with_ends(positions, sequence_ends(lengths.tolist(), n_future))


@torch.no_grad()
def map_keyframes(
    interpolator: torch.nn.Module,
    decoder: torch.nn.Module,
    boundary_emb: Tensor,
    frames: Tensor,
    lengths: Tensor,
    n_keyframes: int,
    keyframe_cost: KeyframeCost,
    scores: Tensor | None = None,
    boundary_weight: float = 0.0,
    weights: Tensor | None = None,
    costs: Tensor | None = None,
    keep: Tensor | None = None,
) -> list[list[int]]:
    """The most likely keyframes given the frames: interpolation BCE, a price per keyframe and,
    optionally, the keyframe predictor's boundary scores as a prior.

    Minimises ``Σ_segments BCE + keyframe_cost · (#keyframes) − boundary_weight · Σ_keyframes s``
    exactly (our discovery rule "map", docs/decisions.md).

    Args:
        boundary_emb: (B, N + 1, E) embeddings on the extended index; frames: (B, N, D) in [0, 1].
        lengths: (B,) valid future frames.
        scores: (B, N) boundary logits, or None for the interpolation cost alone.
        weights: (B, N, D) pixel weights of the frames, None for the plain BCE.
        costs: (B, N, S) the clips' interpolation BCE if already known (windows of one video share
            them: :func:`keyin.decode.segment_costs.window_costs`), else None.
        keep: (B, N, S) bool, the only segments it may use (:func:`candidate_keep`: only their
            frames are rendered), None for all.
    Returns:
        Per clip, the interior keyframe positions.
    """
    max_offset = interpolator.max_offset
    if costs is not None and (weights is not None or costs.shape != (*frames.shape[:2], max_offset)):
        raise ValueError(f"costs must be the (B, N, S) = {(*frames.shape[:2], max_offset)} plain BCE of the clips' "
                         f"segments (no pixel weights), got {tuple(costs.shape)}"
                         + (" with pixel weights" if weights is not None else ""))

    def segment_costs(rows: Tensor, length: int) -> Tensor:
        rows = rows.to(boundary_emb.device)
        kept = None if keep is None else keep[rows.to(keep.device), :length]
        if costs is None:
            bce = interpolation_costs(
                interpolator, decoder, boundary_emb[rows, : length + 1], frames[rows, :length],
                None if weights is None else weights[rows, :length], keep=kept,
            )
        else:
            bce = costs[rows.to(costs.device), :length]
            if kept is not None:
                kept = kept.to(bce.device)
                if not torch.isfinite(bce[kept]).all():
                    raise ValueError("costs lack segments that keep prices (inf where a cost is needed): compute "
                                     "them for at least the kept segments (keyin.pipelines.discover.video_segments)")
                bce = bce.masked_fill(~kept, float("inf"))
        if scores is not None and boundary_weight:
            bce = bce + boundary_weight * boundary_segment_costs(scores[rows, :length].float(), max_offset).to(bce.device)
        return bce  # best_segmentation moves it to the CPU

    return decode_by_length(segment_costs, lengths.cpu(), n_keyframes, max_offset, keyframe_cost)


class SegmentationDiscoverer:
    """Keyframes = the exact best segmentation under a trained stage-1 model (see module doc); what
    ``keyin-eval ckpt=<stage-1 checkpoint>`` scores.

    Args:
        stage1: an :class:`keyin.lit.interpolator.InterpolatorModule` (frozen, eval mode).
        n_keyframes: M.
    """

    def __init__(self, stage1: torch.nn.Module, n_keyframes: int) -> None:
        self.stage1, self.n_keyframes = stage1.eval(), n_keyframes

    @torch.no_grad()
    def __call__(self, clips: Tensor, future_length: Tensor) -> list[list[int]]:
        """Keyframe positions of (B, L, C, H, W) clips with (B,) valid future frames, each clip
        segmented within its own frames by the pixel BCE of its interpolations
        (:func:`with_sequence_ends` adds the end of a sequence that stops inside the window)."""
        n_cond = self.stage1.hparams.n_cond
        clips = clips.to(self.stage1.device)
        boundary_emb = self.stage1.encoder(clips)[:, n_cond - 1 :]  # (B, N + 1, E)
        frames = clips[:, n_cond:].flatten(2)
        weights = future_pixel_weights(self.stage1.pixel_weights(clips), n_cond)

        def segment_costs(rows: Tensor, length: int) -> Tensor:
            rows = rows.to(boundary_emb.device)
            return interpolation_costs(
                self.stage1.interpolator, self.stage1.decoder, boundary_emb[rows, : length + 1], frames[rows, :length],
                None if weights is None else weights[rows, :length],
            )

        lengths = future_length.cpu()
        positions = decode_by_length(segment_costs, lengths, self.n_keyframes, self.stage1.interpolator.max_offset)
        return with_sequence_ends(positions, lengths, frames.shape[1])


@dataclass(frozen=True)
class PosteriorRead:
    """What KEYIN's rules read of a model on clips: the posterior mean, its offset evidence read along
    the argmax chain (what the readout reads).

    Attributes:
        model: the :class:`keyin.models.KEYIN` read; clips: (B, L, C, H, W) in [0, 1];
        future_length: (B,) valid future frames; embeddings: (B, L, E) the clips' frame embeddings;
        keys: the keyframe predictor's output (``offset_probs`` (B, M, S), ``boundary_scores`` (B, N) or None).
    """

    model: KEYIN
    clips: Tensor
    future_length: Tensor
    embeddings: Tensor
    keys: KeyframeOutput


@torch.no_grad()
def read_posterior(model: KEYIN, clips: Tensor, future_length: Tensor) -> PosteriorRead:
    """The posterior mean of a trained ``model`` (eval mode) on (B, L, C, H, W) clips with (B,) valid future frames."""
    embeddings, keys = model.keyframes(clips, future_length, mode="posterior", sample=False, chain="argmax")
    return PosteriorRead(model, clips, future_length, embeddings, keys)


def candidate_keep(read: PosteriorRead, candidate_logit: float) -> Tensor:
    """(B, N, S) bool, the segments between frames whose boundary logit is ≥ ``candidate_logit``
    (:func:`keyin.decode.segment_costs.candidate_segments`), the only ones ``map_pruned`` prices."""
    predictor = read.model.predictor
    return candidate_segments(read.keys.boundary_scores >= candidate_logit, read.future_length, predictor.max_offset,
                              predictor.n_keyframes)


@torch.no_grad()
def keyin_keyframe_probabilities(model: KEYIN, clips: Tensor, future_length: Tensor) -> Tensor:
    """How sure KEYIN is of a keyframe at each future frame: the probability of one there under the
    posterior mean's offsets, read along their argmax chain as the rules read them (:func:`read_posterior`).

    Args:
        model: a trained :class:`keyin.models.KEYIN` in eval mode.
        clips: (B, L, C, H, W) in [0, 1]; future_length: (B,) valid future frames.
    Returns:
        (B, N) probabilities (:func:`keyin.decode.offsets.keyframe_probabilities`).
    """
    return keyframe_probabilities(read_posterior(model, clips, future_length).keys.offset_probs, clips.shape[1] - model.n_cond)
