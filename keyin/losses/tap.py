"""Time-agnostic prediction's minimum-over-time loss (Jayaraman et al. 2019; paper §4.2).

TAP predicts one frame between a start frame ``I_a`` and a goal frame ``I_b`` of a clip and is
scored against whichever admissible frame it resembles most: the loss is the minimum over the
admissible t of the frame's BCE, so the network may pick its own time. Admissible are the frames
``a + margin < t < b - margin`` inside the clip's valid frames (docs/architecture.md, "Baselines": candidates
``a < t < b`` minus an end margin); padding never is.

Frame indices here run over the whole clip, conditioning frames included (0 … L-1).
"""

from __future__ import annotations

import torch
import torch.nn.functional as F
from torch import Tensor


def admissible_frames(start: Tensor, goal: Tensor, n_valid: Tensor, length: int, margin: int) -> Tensor:
    """Which frames a prediction between ``start`` and ``goal`` may be matched with.

    Args:
        start, goal: (B,) frame indices a < b.
        n_valid: (B,) valid frames of each clip; frames from n_valid on are padding.
        length: L, frames per clip.
        margin: frames excluded next to each end besides a and b themselves (≥ 0).
    Returns:
        (B, L) bool, True where a + margin < t < b - margin and t < n_valid.
    """
    steps = torch.arange(length, device=start.device)[None]  # (1, L)
    inside = (steps > (start + margin)[:, None]) & (steps < (goal - margin)[:, None])
    return inside & (steps < n_valid[:, None])


def shortest_gap(margin: int) -> int:
    """The shortest b - a that leaves one admissible frame: a, margin frames, t, margin frames, b."""
    return 2 * margin + 2


def _uniform_integers(low: Tensor, high: Tensor) -> Tensor:
    """One integer drawn uniformly from [low, high] (inclusive) per entry of (B,) bounds."""
    draws = torch.rand(low.shape, device=low.device)
    return torch.minimum(low + (draws * (high - low + 1)).long(), high)  # the minimum guards rounding of draws near 1


def sample_pairs(n_valid: Tensor, shortest: int, longest: int | None = None) -> tuple[Tensor, Tensor]:
    """Training pairs (a, b) inside each clip's valid frames: b - a uniform in [shortest, longest]
    (capped by the clip), then a uniform among the starts that keep b valid.

    Args:
        n_valid: (B,) valid frames of each clip.
        shortest: the least b - a (at least :func:`shortest_gap` of the margin).
        longest: the most b - a; None: the whole valid clip.
    Returns:
        start, goal: (B,) int64 frame indices.
    Raises:
        ValueError: if a clip has fewer than ``shortest + 1`` valid frames.
    """
    last = n_valid - 1
    too_short = last < shortest
    if too_short.any():
        raise ValueError(
            f"a TAP pair needs clips of at least {shortest + 1} valid frames, got {int(n_valid[too_short][0])}; "
            f"lower the model's min_gap or margin, or use longer clips"
        )
    widest = last if longest is None else last.clamp(max=longest)
    gap = _uniform_integers(torch.full_like(last, shortest), widest)
    start = _uniform_integers(torch.zeros_like(last), last - gap)
    return start, start + gap


def whole_clip_pairs(n_valid: Tensor) -> tuple[Tensor, Tensor]:
    """The evaluation pair of each clip: its first and its last valid frame.

    Args:
        n_valid: (B,) valid frames of each clip.
    Returns:
        start (B,) zeros, goal (B,) n_valid - 1.
    """
    return torch.zeros_like(n_valid), n_valid - 1


def pair_images(frames: Tensor, start: Tensor, goal: Tensor) -> tuple[Tensor, Tensor]:
    """The start and goal frames of each clip.

    Args:
        frames: (B, L, C, H, W).
        start, goal: (B,) frame indices.
    Returns:
        start_images, goal_images: (B, C, H, W).
    """
    rows = torch.arange(len(frames), device=frames.device)
    return frames[rows, start], frames[rows, goal]


def frame_bce(logits: Tensor, frames: Tensor, weights: Tensor | None = None) -> Tensor:
    """BCE of one predicted frame against every frame of its clip, summed over pixels.

    Per pixel BCE(x, y) = softplus(x) - y·x for a logit x, so the L comparisons are batched dot
    products and no (B, L, C, H, W) copy of the prediction is made.

    Args:
        logits: (B, C, H, W) predicted logits.
        frames: (B, L, C, H, W) targets in [0, 1].
        weights: (B, L, C, H, W) pixel weights of the targets (keyin/losses/image.py), or None.
    Returns:
        (B, L) per-frame BCE.
    """
    flat_logits = logits.flatten(1)  # (B, D)
    flat_frames = frames.flatten(2)  # (B, L, D)
    softplus = F.softplus(flat_logits)
    if weights is None:
        matches = torch.einsum("bld,bd->bl", flat_frames, flat_logits)  # (B, L)
        return softplus.sum(-1, keepdim=True) - matches
    flat_weights = weights.flatten(2)
    return torch.einsum("bld,bd->bl", flat_weights, softplus) - torch.einsum(
        "bld,bd->bl", flat_weights * flat_frames, flat_logits
    )


def entropy_floor(frames: Tensor) -> Tensor:
    """(B, L) the least BCE a prediction can reach on each frame: Σ H(y) over its pixels (0 for
    binary frames), from (B, L, C, H, W) frames in [0, 1]."""
    # Σ -[y log y + (1 - y) log(1 - y)]; not F.binary_cross_entropy, which CUDA autocast refuses
    return -(torch.special.xlogy(frames, frames) + torch.special.xlogy(1 - frames, 1 - frames)).flatten(2).sum(-1)


def min_over_time_bce(
    logits: Tensor, frames: Tensor, admissible: Tensor, weights: Tensor | None = None
) -> tuple[Tensor, Tensor]:
    """TAP's loss: the BCE of the prediction against its best-matching admissible frame.

    The frame is chosen by the plain BCE above what a perfect prediction of each frame would cost
    (:func:`entropy_floor`, i.e. the KL to the frame), so that no frame wins for being easier to
    reproduce: neither for holding less entropy nor, under per-frame pixel weights (changed pixels weigh
    more, keyin/losses/image.py), for weighing fewer pixels, which made the frames next to the start
    the cheapest whatever the prediction (docs/baselines.md). The loss is the chosen frame's BCE with
    its weights. The logits form needs no clipping of probabilities (docs/architecture.md, "Clamps and precision"). The gradient
    reaches the prediction through the chosen frame only.

    Args:
        logits: (B, C, H, W) predicted logits.
        frames: (B, L, C, H, W) the clips, in [0, 1].
        admissible: (B, L) bool (:func:`admissible_frames`); every row needs one True.
        weights: (B, L, C, H, W) pixel weights of the frames, or None for the plain BCE.
    Returns:
        loss: (B,) the chosen admissible frame's (weighted) BCE summed over pixels;
        argmin: (B,) int64, that t.
    Raises:
        ValueError: if a clip has no admissible frame.
    """
    if not admissible.any(dim=1).all():
        raise ValueError("a clip has no admissible frame for TAP's minimum over time; widen its (start, goal) pair")
    plain = frame_bce(logits, frames)  # (B, L)
    argmin = (plain - entropy_floor(frames)).masked_fill(~admissible, float("inf")).argmin(dim=1)
    per_frame = plain if weights is None else frame_bce(logits, frames, weights)
    return per_frame.gather(1, argmin[:, None]).squeeze(1), argmin


def pair_bce(
    logits: Tensor, frames: Tensor, n_valid: Tensor, start: Tensor, goal: Tensor, margin: int,
    weights: Tensor | None = None,
) -> tuple[Tensor, Tensor]:
    """The min-over-time loss of the network's predictions between ``start`` and ``goal``.

    Args:
        logits: (B, C, H, W) the predictions between each clip's ``start`` and ``goal`` frames (:func:`pair_images`).
        frames: (B, L, C, H, W) the clips, in [0, 1].
        n_valid: (B,) valid frames of each clip.
        start, goal: (B,) frame indices of each pair.
        margin: as in :func:`admissible_frames`.
        weights: (B, L, C, H, W) pixel weights of the frames, or None.
    Returns:
        loss (B,) and argmin (B,) of :func:`min_over_time_bce`.
    """
    admissible = admissible_frames(start, goal, n_valid, frames.shape[1], margin)
    return min_over_time_bce(logits, frames, admissible, weights)


def pair_autoencoding_bce(
    reconstruction: Tensor, frames: Tensor, start: Tensor, goal: Tensor, weights: Tensor | None = None
) -> Tensor:
    """BCE of the start and goal frames decoded from their own embeddings.

    Args:
        reconstruction: (B, 2, C, H, W) logits of each clip's start and goal frames decoded from their own embeddings.
        frames: (B, L, C, H, W) the clips, in [0, 1].
        start, goal: (B,) frame indices of each pair.
        weights: (B, L, C, H, W) pixel weights of the frames, or None.
    Returns:
        (B,) summed over pixels and both frames.
    """
    images = torch.stack(pair_images(frames, start, goal), dim=1)  # (B, 2, C, H, W)
    pair_weights = None if weights is None else torch.stack(pair_images(weights, start, goal), dim=1)
    bce = F.binary_cross_entropy_with_logits(reconstruction, images, pair_weights, reduction="none")
    return bce.flatten(1).sum(-1)


def argmin_times(argmin: Tensor, start: Tensor, goal: Tensor, margin: int) -> tuple[Tensor, Tensor]:
    """Where in time the chosen frames lie: TAP "often simply predicts the final image" (paper §4, on Table 2).

    Args:
        argmin: (B,) chosen frames (:func:`min_over_time_bce`).
        start, goal: (B,) the pairs they were chosen between.
        margin: the end margin of :func:`admissible_frames`.
    Returns:
        relative: (B,) float, (t - a) / (b - a);
        at_last: (B,) bool, t is the last admissible frame b - margin - 1.
    """
    relative = (argmin - start).float() / (goal - start).float()
    return relative, argmin == goal - margin - 1
