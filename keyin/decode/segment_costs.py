"""Segment costs for the exact segmentation (:mod:`keyin.decode.segmentation`).

Every in-clip segment of a clip scored by how badly the frozen interpolator renders it between the
*true* boundary embeddings (pixel BCE, or the cheap squared embedding error), or by per-frame
boundary scores so that the best segmentation is their most likely boundary set.
"""

from __future__ import annotations

import torch
from torch import Tensor

from keyin.data.segments import all_segments, segment_frames
from keyin.decode.segmentation import count_tables
from keyin.losses.interpolation import interpolation_bce
from keyin.models.interpolator import interpolate_segments


@torch.no_grad()
def interpolation_costs(
    interpolator: torch.nn.Module,
    decoder: torch.nn.Module,
    boundary_emb: Tensor,
    frames: Tensor,
    weights: Tensor | None = None,
    chunk: int = 1024,
    n_starts: int | None = None,
    keep: Tensor | None = None,
) -> Tensor:
    """Summed pixel BCE of interpolating every in-clip segment between true boundary embeddings.

    Args:
        interpolator: a :class:`keyin.models.Interpolator`, run with z = 0.
        decoder: the decoder it was trained with (returns logits).
        boundary_emb: (B, N + 1, E) embeddings on the extended index (K^0, then the N future frames).
        frames: (B, N, D) the future frames in [0, 1], flattened.
        weights: (B, N, D) their pixel weights (keyin/losses/image.py), None for the plain BCE.
        chunk: segments per interpolator/decoder call.
        n_starts: only the segments starting at the first ``n_starts`` extended indices (the others
            stay ``inf``); None: all.
        keep: (B, N, S) bool, only the segments marked (:func:`candidate_segments`; the others stay
            ``inf``); None: all.
    Returns:
        (B, N, S) costs, ``inf`` where the segment leaves the clip.
    """
    batch, n_ext, _ = boundary_emb.shape
    n_future, max_offset, device = n_ext - 1, interpolator.max_offset, boundary_emb.device
    costs = torch.full((batch, n_future, max_offset), float("inf"), device=device)
    segments = all_segments(batch, 0, n_future, range(1, max_offset + 1))  # every in-clip segment, on the extended index
    clip, start, offset = (index.to(device) for index in segments)
    kept = start < (n_future if n_starts is None else n_starts)
    if keep is not None:
        if keep.dtype != torch.bool or keep.shape != costs.shape:
            raise ValueError(f"keep must be a bool mask of shape {tuple(costs.shape)}, got {keep.dtype} {tuple(keep.shape)}")
        kept &= keep.to(device)[clip, start, offset - 1]
    clip, start, offset = clip[kept], start[kept], offset[kept]
    for first in range(0, len(clip), chunk):
        segments = clip[first : first + chunk], start[first : first + chunk], offset[first : first + chunk]
        bce, _, _ = interpolation_bce(interpolator, None, decoder, boundary_emb, frames, weights, segments, "mean", first_frame=1)
        costs[segments[0], segments[1], segments[2] - 1] = bce
    return costs


@torch.no_grad()
def video_interpolation_costs(
    interpolator: torch.nn.Module,
    decoder: torch.nn.Module,
    embeddings: Tensor,
    frames: Tensor,
    block: int = 256,
    keep: Tensor | None = None,
) -> Tensor:
    """:func:`interpolation_costs` of every segment of a whole video, for windows to share.

    A segment's cost reads only its two boundary embeddings and the frames between (plain BCE: no
    window-relative pixel weights), so a window's costs are rows of these (:func:`window_costs`) and
    overlapping windows need not compute them twice. Computed ``block`` starts at a time.

    Args:
        embeddings: (T, E) the encoder's embedding of every kept frame, T ≥ 2.
        frames: (T, D) those frames, flattened: in [0, 1], or uint8 (0-255, turned into [0, 1] a block at
            a time on the embeddings' device, so that a long video's pixels stay small).
        keep: (T - 1, S) bool, only the segments marked (the others stay ``inf``); None: all.
    Returns:
        (T - 1, S) the cost of the segment from frame ``t`` to frame ``t + o + 1`` at ``[t, o]``,
        ``inf`` where it leaves the video.
    """
    n_frames, max_offset = len(embeddings), interpolator.max_offset
    if n_frames < 2 or len(frames) != n_frames:
        raise ValueError(f"a video's segment costs need T ≥ 2 embeddings and as many frames, got {n_frames} and {len(frames)}")
    if keep is not None and (keep.dtype != torch.bool or keep.shape != (n_frames - 1, max_offset)):
        raise ValueError(f"keep must be a bool mask of shape (T - 1, S) = {(n_frames - 1, max_offset)}, got {keep.dtype} "
                         f"{tuple(keep.shape)}")
    costs = []
    for first in range(0, n_frames - 1, block):
        last = min(first + block + max_offset, n_frames)  # the block's starts and the frames they reach
        if keep is not None and not keep[first : first + block].any():
            costs.append(torch.full((min(block, n_frames - 1 - first), max_offset), float("inf"), device=embeddings.device))
            continue
        pixels = frames[first + 1 : last].to(embeddings.device)
        pixels = pixels.float().div_(255.0) if pixels.dtype == torch.uint8 else pixels
        block_keep = None
        if keep is not None:  # the block's rows of keep, on its own (last - first - 1) starts
            block_keep = keep.new_zeros(1, last - first - 1, max_offset)
            block_keep[0, : min(block, n_frames - 1 - first)] = keep[first : first + block]
        part = interpolation_costs(interpolator, decoder, embeddings[None, first:last], pixels[None], n_starts=block,
                                   keep=block_keep)
        costs.append(part[0, :block])
    return torch.cat(costs)


def candidate_segments(candidates: Tensor, lengths: Tensor, max_offset: int, n_keyframes: int) -> Tensor:
    """The segments a segmentation may use when each of its keyframes must be a candidate frame.

    Each clip's start (K^0) and closing boundary (its last valid frame) are always boundaries. A clip
    whose candidates admit no segmentation into at most M gaps of at most S keeps every segment, so
    that its best segmentation is the unrestricted one.

    Args:
        candidates: (B, N) bool, the future positions that may be keyframes.
        lengths: (B,) valid future frames, each ≥ 1.
        max_offset: S; n_keyframes: M.
    Returns:
        (B, N, S) bool: ``[b, a, o - 1]`` whether the segment from extended index ``a`` to ``a + o``
        lies in the clip's valid frames and both its ends may be boundaries.
    """
    batch, n_future = candidates.shape
    device = candidates.device
    lengths = lengths.to(device)
    index = torch.arange(n_future + 1, device=device)  # the extended index
    allowed = torch.cat([candidates.new_ones(batch, 1), candidates.bool()], dim=1)  # (B, N + 1)
    allowed = (allowed & (index < lengths[:, None])) | (index == lengths[:, None])
    end = torch.arange(n_future, device=device)[:, None] + torch.arange(1, max_offset + 1, device=device)  # (N, S)
    inside = end[None] <= lengths[:, None, None]  # (B, N, S)
    keep = allowed[:, :n_future, None] & allowed[:, end.clamp(max=n_future)] & inside
    free = torch.zeros(keep.shape).masked_fill_(~keep.cpu(), float("inf"))  # the segmentation DP on 0/inf costs
    best, _ = count_tables(free, n_keyframes)  # (M + 1, B, N + 1): finite where m gaps reach index k
    feasible = torch.isfinite(best[:, torch.arange(batch), lengths.cpu()]).any(dim=0).to(device)
    return torch.where(feasible[:, None, None], keep, inside)


def window_costs(video_costs: Tensor, firsts: Tensor, lengths: Tensor, n_future: int) -> Tensor:
    """Windows' segment costs cut from their video's (:func:`video_interpolation_costs`).

    Args:
        video_costs: (T - 1, S).
        firsts: (B,) the video frame at each window's extended index 0 (K^0, its last conditioning frame).
        lengths: (B,) each window's valid future frames.
        n_future: N.
    Returns:
        (B, N, S) as :func:`interpolation_costs` of the windows, ``inf`` where a segment leaves a
        window's valid frames.
    """
    (n_starts, max_offset), device = video_costs.shape, video_costs.device
    firsts, lengths = firsts.to(device), lengths.to(device)
    if (firsts < 0).any() or (firsts + lengths > n_starts).any():
        raise ValueError(f"windows must lie inside the video's {n_starts + 1} frames: first frames {firsts.tolist()}, "
                         f"valid future frames {lengths.tolist()}")
    steps = torch.arange(n_future, device=device)
    rows = firsts[:, None] + steps  # (B, N)
    costs = video_costs[rows.clamp(max=n_starts - 1)]  # (B, N, S)
    end = steps[None, :, None] + torch.arange(1, max_offset + 1, device=device)  # (1, N, S): start + offset
    return costs.masked_fill(end > lengths[:, None, None], float("inf"))


@torch.no_grad()
def embedding_costs(interpolator: torch.nn.Module, boundary_emb: Tensor) -> Tensor:
    """Summed squared embedding error of every in-clip segment: the decoder-free, cheap variant.

    Args:
        interpolator: a :class:`keyin.models.Interpolator`, run with z = 0.
        boundary_emb: (B, N + 1, E) embeddings on the extended index.
    Returns:
        (B, N, S) costs, ``inf`` where the segment leaves the clip.
    """
    batch, n_ext, _ = boundary_emb.shape
    n_future, max_offset = n_ext - 1, interpolator.max_offset
    segments = all_segments(batch, 0, n_future, range(1, max_offset + 1))
    clip, start, offset = (index.to(boundary_emb.device) for index in segments)
    predicted, valid, _ = interpolate_segments(interpolator, None, boundary_emb, clip, start, offset, "mean")  # (R, S, E)
    frames, _ = segment_frames(start, offset, max_offset)
    targets = boundary_emb[clip[:, None], frames]  # (R, S, E)
    per_segment = (((predicted - targets) ** 2).sum(-1) * valid).sum(-1)  # (R,)
    costs = boundary_emb.new_full((batch, n_future, max_offset), float("inf"))
    costs[clip, start, offset - 1] = per_segment
    return costs


def boundary_segment_costs(scores: Tensor, max_offset: int) -> Tensor:
    """Segment costs under which the best segmentation is the MAP of per-frame boundary scores.

    With boundary probability ``p_j = σ(s_j)`` per future position, the log-likelihood of a set of
    interior boundaries is ``Σ_boundaries log p + Σ_others log(1 - p)``; up to a constant, each
    boundary adds its logit ``s_j``. A segment ending at extended index ``e < N`` (position
    ``e - 1``) therefore costs ``-s[e - 1]``; the segment closing the clip at ``N`` costs nothing.

    Args:
        scores: (B, N) boundary logits of the future positions.
        max_offset: S.
    Returns:
        (B, N, S) costs for :func:`best_segmentation`, ``inf`` where a segment leaves the clip.
    """
    batch, n_future = scores.shape
    _, start, offset = (index.to(scores.device) for index in all_segments(1, 0, n_future, range(1, max_offset + 1)))
    end = start + offset  # extended index of the segment's closing boundary
    per_segment = torch.where(end < n_future, -scores[:, (end - 1).clamp(max=n_future - 1)], scores.new_zeros(()))
    costs = scores.new_full((batch, n_future, max_offset), float("inf"))
    costs[:, start, offset - 1] = per_segment
    return costs
