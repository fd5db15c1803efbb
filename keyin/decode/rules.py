"""Keyframe rules built on the exact segmentation: ``boundaries``, ``map`` and the stage-1 gate.

KEYIN's stage 2 can only find keyframes that make the frozen interpolator's job easier. Given the
true frames, the best it could possibly do is the hard segmentation that minimises the summed
interpolation BCE; its F1 against the ground truth measures whether an interpolator is good enough
for stage 2 to discover the ground truth, before stage 2 is trained (PROTOTYPE-FINDINGS §4).
Every rule returns, per clip, keyframe positions inside the clip's valid frames.
"""

from __future__ import annotations

import torch
from torch import Tensor

from keyin.decode.ends import sequence_ends, with_ends
from keyin.decode.names import BOUNDARY_SCORE_RULES, KEYIN_RULES, SEGMENT_COST_RULES, VARIANT_RULES  # noqa: F401
from keyin.decode.offsets import keyframe_probabilities, offset_keyframes
from keyin.decode.segment_costs import boundary_segment_costs, candidate_segments, interpolation_costs
from keyin.decode.segmentation import KeyframeCost, decode_by_length
from keyin.losses.image import future_pixel_weights
from keyin.models.keyin import KEYIN

# The rules by their cost per kept frame, cheapest first: boundaries and offsets run the encoder and the
# posterior once (~0.3 ms per kept frame at Brownian size), map also decodes every segment's frames (~7 ms
# in keyin-discover), map_pruned only those of the segments between candidate keyframes (~1.2 ms;
# benchmarks/results/discover_speed_rules_brownian.md, discover_speed_map_pruned_brownian_1thread.md).
RULES_BY_COST = ("boundaries", "offsets", "map_pruned", "map")
MAP_CANDIDATE_LOGIT = -4.0  # map_pruned: the boundary logit a frame needs to be a candidate keyframe (docs/decisions.md)
FAST_RULE_TOLERANCE = 0.01  # how far below map's validation F1 a cheaper rule may be and still be chosen


def fastest_rule(val_f1: dict[str, float], tolerance: float = FAST_RULE_TOLERANCE) -> str:
    """The cheapest rule of :data:`RULES_BY_COST` whose validation F1 is at least ``map``'s less
    ``tolerance`` (``map`` itself when no cheaper one is); rules missing from ``val_f1`` are passed over.

    Raises:
        ValueError: ``val_f1`` has no ``map`` score to compare with.
    """
    if "map" not in val_f1:
        raise ValueError(f"fastest_rule compares with map's validation F1, which {sorted(val_f1)} lacks")
    return next(rule for rule in RULES_BY_COST if rule in val_f1 and val_f1[rule] >= val_f1["map"] - tolerance)


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
        keep: (B, N, S) bool, the only segments it may use (:func:`map_pruned_segments`: only their
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


@torch.no_grad()
def keyin_keyframes(
    model: KEYIN,
    clips: Tensor,
    future_length: Tensor,
    rule: str = "offsets",
    keyframe_cost: KeyframeCost = 0.0,
    boundary_weight: float = 0.0,
    pixel_weights: Tensor | None = None,
    costs: Tensor | None = None,
    candidate_logit: float = MAP_CANDIDATE_LOGIT,
) -> list[list[int]]:
    """KEYIN's keyframes of clips, in posterior mode with the posterior mean, by one of its rules.

    Args:
        model: a trained :class:`keyin.models.KEYIN` in eval mode.
        clips: (B, L, C, H, W) in [0, 1]; future_length: (B,) valid future frames.
        rule: "offsets" (the paper's: argmax offsets, positions by their sums, §3.9; with offset
            evidence each δ^t reads the previous keyframe where the argmax offsets put it),
            "boundaries" (with offset evidence: the most likely keyframe set under LSTM_inf's
            per-frame boundary scores, within M gaps of at most S) or "map" (the exact best
            segmentation under the frozen interpolator's pixel BCE with ``keyframe_cost`` per
            keyframe, or each clip's knee count for ``"knee"`` (label-free), plus
            ``boundary_weight`` times the boundary scores where there are any), "map_pruned" ("map" whose
            keyframes must have a boundary logit ≥ ``candidate_logit``: only the segments between such
            frames are rendered, :func:`map_pruned_segments`) or "segmentation" ("map" without stage 2's
            boundary scores: stage 1's exact segmentation at the same price).
        pixel_weights: (B, N, D) weights of the future pixels in the BCE of "map", None for plain BCE.
        costs: (B, N, S) that BCE of every segment if already known (see :func:`map_keyframes`; for
            "map_pruned", of at least the segments it prices).
        candidate_logit: "map_pruned"'s least boundary logit of a keyframe.
    Returns:
        Per clip, the keyframe positions inside its valid frames; "boundaries" and the map rules add the
        end of a sequence that stops inside the window (:func:`with_sequence_ends`).
    """
    if rule not in KEYIN_RULES:
        raise ValueError(f"rule must be one of {KEYIN_RULES}, got {rule!r}")
    # the posterior mean, its offset evidence read along the argmax path (what the readout reads)
    embeddings, keys = model.keyframes(clips, future_length, mode="posterior", sample=False, chain="argmax")
    if costs is not None and rule not in SEGMENT_COST_RULES:
        raise ValueError(f"rule {rule!r} reads no segment costs; pass costs only with {SEGMENT_COST_RULES}")
    if rule in BOUNDARY_SCORE_RULES and keys.boundary_scores is None:
        raise ValueError(f"rule {rule!r} needs the boundary scores of offset_evidence")
    if rule == "offsets":
        return offset_keyframes(keys.offset_probs, future_length)
    n_future, lengths = clips.shape[1] - model.n_cond, future_length.cpu()
    if rule == "boundaries":
        interior = boundary_keyframes(keys.boundary_scores, lengths, model.predictor.n_keyframes, model.predictor.max_offset)
    else:
        keep = _candidate_keep(keys.boundary_scores, lengths, candidate_logit, model) if rule == "map_pruned" else None
        interior = map_keyframes(
            model.interpolator, model.decoder, embeddings[:, model.n_cond - 1 :], clips[:, model.n_cond :].flatten(2),
            future_length, model.predictor.n_keyframes, keyframe_cost,
            None if rule == "segmentation" else keys.boundary_scores, boundary_weight, weights=pixel_weights,
            costs=costs, keep=keep,
        )
    return with_sequence_ends(interior, lengths, n_future)


def _candidate_keep(boundary_scores: Tensor, lengths: Tensor, candidate_logit: float, model: KEYIN) -> Tensor:
    """(B, N, S) the segments ``map_pruned`` prices: between frames whose boundary logit is ≥ ``candidate_logit``."""
    return candidate_segments(boundary_scores >= candidate_logit, lengths, model.predictor.max_offset,
                              model.predictor.n_keyframes)


@torch.no_grad()
def map_pruned_segments(model: KEYIN, clips: Tensor, future_length: Tensor, candidate_logit: float) -> Tensor:
    """The segments ``map_pruned`` prices in each clip, read as :func:`keyin_keyframes` reads them
    (keyin-discover renders the union over a video's windows once).

    Args:
        model: a trained :class:`keyin.models.KEYIN` with offset evidence, in eval mode.
        clips: (B, L, C, H, W) in [0, 1]; future_length: (B,) valid future frames.
    Returns:
        (B, N, S) bool (:func:`keyin.decode.segment_costs.candidate_segments`).
    """
    _, keys = model.keyframes(clips, future_length, mode="posterior", sample=False, chain="argmax")
    if keys.boundary_scores is None:
        raise ValueError("rule 'map_pruned' needs the boundary scores of offset_evidence")
    return _candidate_keep(keys.boundary_scores, future_length, candidate_logit, model)


@torch.no_grad()
def keyin_keyframe_probabilities(model: KEYIN, clips: Tensor, future_length: Tensor) -> Tensor:
    """How sure KEYIN is of a keyframe at each future frame: the probability of one there under the
    posterior mean's offsets, read along their argmax chain as :func:`keyin_keyframes` reads them.

    Args:
        model: a trained :class:`keyin.models.KEYIN` in eval mode.
        clips: (B, L, C, H, W) in [0, 1]; future_length: (B,) valid future frames.
    Returns:
        (B, N) probabilities (:func:`keyin.decode.offsets.keyframe_probabilities`).
    """
    _, keys = model.keyframes(clips, future_length, mode="posterior", sample=False, chain="argmax")
    return keyframe_probabilities(keys.offset_probs, clips.shape[1] - model.n_cond)
