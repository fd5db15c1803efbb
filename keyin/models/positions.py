"""Where keyframes and frames sit, given offset distributions (paper Alg. 2, §3.1-3.2).

Index conventions (docs/architecture.md, "Index conventions"): ``offset_probs[..., a]`` is the probability of offset
``a + 1``; keyframe ``K^0`` sits at position -1; the future frames ``I_0 ... I_{N-1}`` sit at
positions ``0 ... N-1``. Every distribution over positions is stored on the *extended index*
``k = position + 1`` (``k = 0`` is ``K^0``), of length ``L_ext = M * S + 1`` (the same section).
The soft keyframe loss (:mod:`keyin.losses.soft_keyframe`) and the model's readout video
(:meth:`keyin.models.KEYIN.argmax_video`) both build on these.
"""

import torch
import torch.nn.functional as F
from torch import Tensor

PROB_EPS = 1e-6
"""Clamp of BCE probabilities, coverage and ``c^t`` normalisers (docs/architecture.md, "Clamps and precision")."""


def initial_position(batch: int, n_ext: int, like: Tensor) -> Tensor:
    """``D^0``: K^0 at extended index 0 with certainty, (B, L_ext)."""
    position = like.new_zeros(batch, n_ext)
    position[:, 0] = 1.0
    return position


def shifted_positions(previous_pos: Tensor, max_offset: int) -> Tensor:
    """``X^t[b, a, k] = D^{t-1}[b, k - a - 1]``: where keyframe t sits if its offset is a + 1.

    Args:
        previous_pos: (B, L_ext) ``D^{t-1}``.
        max_offset: S.
    Returns:
        (B, S, L_ext), zero where ``k - a - 1 < 0``.
    """
    n_ext = previous_pos.shape[-1]
    # windows[b, k, s] = padded[b, k + s] = D^{t-1}[b, k + s - S]; flipping s gives X.
    padded = F.pad(previous_pos, (max_offset, 0))
    windows = padded.unfold(-1, max_offset, 1)[:, :n_ext]
    return windows.flip(-1).transpose(-1, -2)


def position_distributions(offset_probs: Tensor) -> tuple[Tensor, Tensor]:
    """Keyframe and per-frame position distributions by shift-and-weight (paper Alg. 2).

    With ``X^t[b, a, k] = D^{t-1}[b, k - a - 1]`` (``D^0 = onehot(k = 0)``):
    ``D^t = Σ_a δ^t[a] X^t[a]`` and ``Wt^t[i] = e^t[i] X^t[i]`` with ``e^t[i] = P(o^t >= i + 1)``.

    Args:
        offset_probs: (B, M, S); entry a is the probability of offset a + 1.
    Returns:
        keyframe_pos: (B, M, L_ext); ``[b, t-1, k]`` = P(keyframe t sits at extended index k).
        frame_pos: (B, M, S, L_ext); ``[b, t-1, i, k]`` = P(output i of segment t exists and sits
            at extended index k).
    """
    batch, n_keys, max_offset = offset_probs.shape
    n_ext = n_keys * max_offset + 1
    # e^t[i] = Σ_{a >= i} δ^t[a]: reverse cumulative sum over offsets.
    exist_probs = offset_probs.flip(-1).cumsum(-1).flip(-1)
    previous_pos = initial_position(batch, n_ext, offset_probs)
    keyframe_pos, shifted_stack = [], []
    for key in range(n_keys):
        shifted = shifted_positions(previous_pos, max_offset)  # (B, S, L_ext)
        previous_pos = torch.einsum("bak,ba->bk", shifted, offset_probs[:, key])
        keyframe_pos.append(previous_pos)
        shifted_stack.append(shifted)
    frame_pos = torch.stack(shifted_stack, dim=1) * exist_probs[..., None]
    return torch.stack(keyframe_pos, dim=1), frame_pos


def future_window(extended: Tensor, n_future: int) -> Tensor:
    """Extended indices 1 ... N (positions 0 ... N-1) of the last dimension (paper Alg. 2)."""
    if extended.shape[-1] < n_future + 1:
        raise ValueError(
            f"M*S = {extended.shape[-1] - 1} positions cannot cover N = {n_future} future frames; "
            "keyin requires M*S >= N (docs/architecture.md, Index conventions)"
        )
    return extended[..., 1 : n_future + 1]


def valid_frame_mask(lengths: Tensor, n_future: int) -> Tensor:
    """Which future positions lie inside each clip (docs/architecture.md, "Padding and masking").

    Args:
        lengths: (B,) int, valid future frames n_b <= N.
        n_future: N.
    Returns:
        (B, N) bool, True at positions j < n_b.
    """
    positions = torch.arange(n_future, device=lengths.device)
    return positions < lengths[:, None]


def _inside_keyframe_pos(keyframe_pos: Tensor, lengths: Tensor, n_future: int) -> Tensor:
    """``D^t`` on positions 0 ... n_b - 1: (B, M, L_ext) → (B, M, N) (paper Alg. 2)."""
    frame_mask = valid_frame_mask(lengths, n_future)
    return future_window(keyframe_pos, n_future) * frame_mask[:, None, :]


def soft_keyframe_targets(
    keyframe_pos: Tensor, lengths: Tensor, future: Tensor, normalize: bool
) -> Tensor:
    """Expected ground-truth keyframes ``K̃^t = Σ_{j<n_b} D^t[j+1] future_j`` (paper §3.2, Alg. 2).

    Args:
        keyframe_pos: (B, M, L_ext) from :func:`position_distributions`.
        lengths: (B,) int, valid future frames n_b.
        future: (B, N, D) future-frame embeddings or flattened images; entries at positions
            >= n_b are ignored (they may hold anything, NaN included).
        normalize: divide by ``max(c^t, 1e-6)`` (expectation given "inside"; our default) instead
            of the paper's unnormalised sum.
    Returns:
        (B, M, D) soft targets.
    """
    n_future = future.shape[1]
    inside_pos = _inside_keyframe_pos(keyframe_pos, lengths, n_future)
    frame_mask = valid_frame_mask(lengths, n_future)
    # A fill, not a product: 0 * NaN padding would still be NaN.
    future = future.masked_fill(~frame_mask[..., None], 0.0)
    targets = torch.bmm(inside_pos, future)
    if normalize:
        targets = targets / inside_pos.sum(-1, keepdim=True).clamp_min(PROB_EPS)
    return targets


def soft_frames(
    frame_pos: Tensor, predicted: Tensor, n_future: int, eps: float = PROB_EPS
) -> tuple[Tensor, Tensor]:
    """Mix the interpolator's outputs into one expected frame per position (paper §3.2, Alg. 2).

    Each position's mixture depends only on the outputs that can land there, so clip lengths play
    no role here: positions >= n_b are dropped by the loss.

    Args:
        frame_pos: (B, M, S, L_ext) from :func:`position_distributions`.
        predicted: (B, M, S, D) interpolated frames ``Î^t_i`` (probabilities or embeddings).
        n_future: N, the number of future positions to produce.
        eps: lower clamp of the coverage denominator.
    Returns:
        mixed: (B, N, D) ``Ĩ_j = Σ_{t,i} Wt[t,i,j+1] Î^t_i / max(cov_j, eps)``; 0 where
            cov_j = 0.
        coverage: (B, N) ``cov_j = P(p^M >= j)``, the probability that position j is predicted.
    """
    batch, n_keys, max_offset, n_pixels = predicted.shape
    frame_weights = future_window(frame_pos, n_future).reshape(
        batch, n_keys * max_offset, n_future
    )
    coverage = frame_weights.sum(1)
    # Normalising the (B, M·S, N) weights instead of the (B, N, D) product saves a pass over D.
    mixing_weights = frame_weights / coverage.clamp_min(eps)[:, None, :]
    mixed = torch.bmm(
        mixing_weights.transpose(1, 2), predicted.reshape(batch, n_keys * max_offset, n_pixels)
    )
    return mixed, coverage


def argmax_positions(offset_probs: Tensor) -> Tensor:
    """Most likely position of each keyframe, from argmax offsets (paper §3.1; docs/architecture.md, "Index conventions").

    Args:
        offset_probs: (B, M, S); entry a is the probability of offset a + 1.
    Returns:
        (B, M) positions ``p^t = -1 + Σ_{s<=t} (argmax δ^s + 1)``; -1 is the last conditioning
        frame.
    """
    return (offset_probs.argmax(dim=-1) + 1).cumsum(dim=-1) - 1


def argmax_frames(offset_probs: Tensor, predicted: Tensor, n_future: int) -> Tensor:
    """The video of the most likely offsets (paper §3.1): the soft mixture at one-hot δ.

    Args:
        offset_probs: (B, M, S).
        predicted: (B, M, S, D) interpolated frames.
        n_future: N.
    Returns:
        (B, N, D): frame j is the output of the segment whose argmax offsets cover position j
        (zeros past the last keyframe).
    """
    hard = F.one_hot(offset_probs.argmax(dim=-1), offset_probs.shape[-1]).to(predicted)
    _, frame_pos = position_distributions(hard)
    mixed, _ = soft_frames(frame_pos, predicted, n_future)
    return mixed
