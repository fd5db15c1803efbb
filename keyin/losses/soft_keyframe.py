"""KEYIN's soft keyframe loss (paper Algorithm 2, eq. 3-5) as vectorised tensor operations.

Where keyframes and frames sit given the offsets (the position distributions, the soft frames) is
:mod:`keyin.models.positions`, with its index conventions (docs/architecture.md, "Index conventions").

Clips may have different valid lengths ``n_b <= N`` (``lengths``); positions ``>= n_b`` are
excluded from ``c^t``, from the keyframe targets and from ``L_inter`` (docs/architecture.md, "Padding and masking").
"""

from dataclasses import dataclass

import torch
import torch.nn.functional as F
from torch import Tensor

from keyin.precision import in_float32
from keyin.models.distributions import gaussian_kl
from keyin.models.positions import PROB_EPS, position_distributions, soft_frames, soft_keyframe_targets, valid_frame_mask

IGNORE_OFFSET = -100
"""A keyframe without a teacher offset (``cross_entropy``'s ignore index)."""
REDUCTIONS = ("sum", "per_frame", "per_pixel")
"""How :func:`keyin_loss` reduces its terms, which sets what the β's weigh them against (the paper does
not say; docs/decisions.md): "sum" BCE summed over pixels and frames, ``ℓ_ke`` over embedding dims,
``ℓ_KL`` over latent dims; "per_frame" ``L_inter`` averaged over the clip's valid frames instead (the
keyframe terms are already averaged over keyframes); "per_pixel" every term a mean per scalar: BCE over
pixels and frames, ``ℓ_ke`` over embedding dims, ``ℓ_KL`` over latent dims."""


@dataclass(frozen=True)
class SoftLossConfig:
    """The weights of stage 2's loss (paper eq. 3, :func:`keyin_loss`) and what they weigh against
    (``reduction``, :data:`REDUCTIONS`); ``entropy_bonus`` (an aid the paper does not have) rewards
    w·H(δ), w decaying linearly from ``entropy_bonus`` to 0 over ``entropy_bonus_steps`` training steps."""

    beta_ke: float
    beta_ki: float
    beta_kl: float
    normalize_key_targets: bool = True
    reduction: str = "sum"
    entropy_bonus: float = 0.0
    entropy_bonus_steps: int = 0

    def __post_init__(self) -> None:
        if self.reduction not in REDUCTIONS:
            raise ValueError(f"loss_reduction must be one of {REDUCTIONS}, got {self.reduction!r}")
        if self.entropy_bonus < 0 or (self.entropy_bonus > 0 and self.entropy_bonus_steps < 1):
            raise ValueError(
                f"entropy_bonus must be >= 0 and, when > 0, decay over entropy_bonus_steps >= 1 steps; "
                f"got {self.entropy_bonus} over {self.entropy_bonus_steps}"
            )

    def entropy_weight(self, step: int) -> float:
        """w at training step ``step``."""
        return self.entropy_bonus * max(0.0, 1.0 - step / self.entropy_bonus_steps) if self.entropy_bonus > 0 else 0.0


def in_sequence_probs(keyframe_pos: Tensor, lengths: Tensor) -> Tensor:
    """Probability ``c^t`` that keyframe t lies inside the clip (paper §3.2, Alg. 2).

    Args:
        keyframe_pos: (B, M, L_ext) from :func:`position_distributions`.
        lengths: (B,) int, valid future frames n_b.
    Returns:
        (B, M) ``c^t = Σ_{k=1}^{n_b} D^t[k]``.
    """
    future_pos = keyframe_pos[..., 1:]  # drop k = 0 (K^0): positions 0 ... M*S-1
    return (future_pos * valid_frame_mask(lengths, future_pos.shape[-1])[:, None, :]).sum(-1)


def bce_sum(
    probs: Tensor, targets: Tensor, mask: Tensor | None = None, weights: Tensor | None = None
) -> Tensor:
    """Binary cross-entropy on probabilities, summed over pixels (paper §4; docs/architecture.md, "Clamps and precision").

    Probabilities are clamped to [1e-6, 1 - 1e-6]; mixtures of sigmoid outputs have no logits, so
    the logits form cannot be used.

    Args:
        probs: (..., F, D) predicted probabilities.
        targets: (..., F, D) targets in [0, 1]; masked frames may hold anything.
        mask: (..., F) bool, frames that count; None keeps all.
        weights: (..., F, D) per-pixel weights (keyin/losses/image.py); None weighs all 1.
    Returns:
        (..., F) per-frame BCE summed over D; 0 at masked frames.
    """
    probs = probs.clamp(PROB_EPS, 1 - PROB_EPS)
    if mask is not None:
        # Padding may hold anything; a NaN there would reach the gradient as 0 * NaN.
        targets = targets.masked_fill(~mask[..., None], 0.0)
    # y log p + (1 - y) log(1 - p) rearranged to save two full passes over the pixels.
    log_not_probs = torch.log1p(-probs)
    per_pixel = log_not_probs + targets * (torch.log(probs) - log_not_probs)
    per_frame = -(per_pixel if weights is None else per_pixel * weights).sum(-1)
    if mask is not None:
        per_frame = per_frame.masked_fill(~mask, 0.0)
    return per_frame


def interpolation_loss(
    frame_pos: Tensor, inter_frames_pred: Tensor, future_frames: Tensor, lengths: Tensor,
    pixel_weights: Tensor | None = None,
) -> tuple[Tensor, Tensor, Tensor]:
    """``L_inter`` of each clip (eq. 4 with BCE): the summed BCE of the soft frames Ĩ_j, j < n_b.

    Args:
        frame_pos: (B, M, S, L_ext) from :func:`position_distributions`.
        inter_frames_pred: (B, M, S, D) interpolated frames as probabilities.
        future_frames: (B, N, D) ground truth in [0, 1].
        lengths: (B,) valid future frames n_b.
        pixel_weights: (B, N, D) or None.
    Returns:
        (B,) L_inter, and :func:`soft_frames`' mixture (B, N, D) and coverage (B, N).
    """
    n_future = future_frames.shape[1]
    mixed, coverage = soft_frames(frame_pos, inter_frames_pred, n_future)
    loss = bce_sum(mixed, future_frames, valid_frame_mask(lengths, n_future), pixel_weights).sum(-1)
    return loss, mixed, coverage


def _at_least_float32(tensor: Tensor) -> Tensor:
    """Upcast half/bfloat16 to float32 and keep float64 (docs/architecture.md, "Clamps and precision")."""
    return tensor if tensor.dtype in (torch.float32, torch.float64) else tensor.float()


def keyin_loss(
    offset_probs: Tensor,
    key_emb_pred: Tensor,
    future_emb: Tensor,
    inter_frames_pred: Tensor,
    future_frames: Tensor,
    kl_per_key: Tensor,
    lengths: Tensor,
    beta_ke: float,
    beta_ki: float,
    beta_kl: float,
    normalize_key_targets: bool = True,
    key_frames_pred: Tensor | None = None,
    pixel_weights: Tensor | None = None,
    reduction: str = "sum",
    latent_dim: int | None = None,
) -> dict[str, Tensor]:
    """KEYIN stage-2 loss ``L_key + L_inter`` (paper eq. 3-5; docs/architecture.md, "Reductions").

    ``L_key = Σ_t c^t (β_ki ℓ_ki^t + β_ke ℓ_ke^t + β_KL ℓ_KL^t) / Σ_t c^t`` with
    ``ℓ_ke^t = ‖K̂^{e,t} - K̃^{e,t}‖²`` and ``ℓ_ki^t = BCE_sum(K̂^t, K̃^t)``;
    ``L_inter = Σ_{j<n_b} BCE_sum(Ĩ_j, I_j)``. Sums over pixels, dims and frames; mean over the
    batch. Runs outside autocast, in float32 (float64 inputs stay float64).

    Args:
        offset_probs: (B, M, S) offset distributions δ; entry a is offset a + 1.
        key_emb_pred: (B, M, E) predicted keyframe embeddings K̂^{e,t}.
        future_emb: (B, N, E) embeddings of the future frames.
        inter_frames_pred: (B, M, S, D) interpolated frames Î^t_i as probabilities, D = C·H·W.
        future_frames: (B, N, D) ground-truth future frames in [0, 1].
        kl_per_key: (B, M) ℓ_KL^t, e.g. from :func:`gaussian_kl`.
        lengths: (B,) int, valid future frames n_b <= N.
        beta_ke: weight of the embedding term.
        beta_ki: weight of the keyframe-image term; needs ``key_frames_pred`` when > 0.
        beta_kl: weight of the KL term.
        normalize_key_targets: divide the soft keyframe targets by c^t (docs/architecture.md, "Clamps and precision").
        key_frames_pred: (B, M, D) decoded keyframes K̂^t as probabilities.
        pixel_weights: (B, N, D) weights of the future frames' pixels in ``L_inter``
            (keyin/losses/image.py); None: the plain BCE.
        reduction: one of :data:`REDUCTIONS`; "sum" is the formula above.
        latent_dim: Zk, the dims ``kl_per_key`` was summed over; needed by "per_pixel".
    Returns:
        ``loss`` (scalar); batch means ``key`` (L_key), ``key_emb``, ``kl``, ``inter`` (L_inter)
        and, if beta_ki > 0, ``key_img`` — the terms are c-weighted averages over keyframes and
        carry no β; ``c`` (B, M); ``coverage`` (B, N); ``soft_frames`` (B, N, D) = Ĩ.
    """
    if beta_ki > 0 and key_frames_pred is None:
        raise ValueError("beta_ki > 0 needs key_frames_pred")
    if reduction not in REDUCTIONS:
        raise ValueError(f"reduction must be one of {REDUCTIONS}, got {reduction!r}")
    if reduction == "per_pixel" and latent_dim is None:
        raise ValueError("reduction='per_pixel' needs latent_dim (the KL's dims)")
    with torch.autocast(device_type=offset_probs.device.type, enabled=False):
        offset_probs = _at_least_float32(offset_probs)
        key_emb_pred = _at_least_float32(key_emb_pred)
        future_emb = _at_least_float32(future_emb)
        inter_frames_pred = _at_least_float32(inter_frames_pred)
        future_frames = _at_least_float32(future_frames)
        kl_per_key = _at_least_float32(kl_per_key)

        keyframe_pos, frame_pos = position_distributions(offset_probs)
        in_sequence = in_sequence_probs(keyframe_pos, lengths)
        # Σ_t c^t >= c^1 = 1 for full clips, but clips shorter than S can make it small (§3.3).
        key_weights = in_sequence / in_sequence.sum(-1, keepdim=True).clamp_min(PROB_EPS)

        emb_targets = soft_keyframe_targets(
            keyframe_pos, lengths, future_emb, normalize_key_targets
        )
        key_emb_terms = ((key_emb_pred - emb_targets) ** 2).sum(-1)  # (B, M)
        if reduction == "per_pixel":
            key_emb_terms = key_emb_terms / key_emb_pred.shape[-1]
            kl_per_key = kl_per_key / latent_dim
        per_key = beta_ke * key_emb_terms + beta_kl * kl_per_key
        terms = {"key_emb": key_emb_terms, "kl": kl_per_key}
        if beta_ki > 0:
            img_targets = soft_keyframe_targets(
                keyframe_pos, lengths, future_frames, normalize_key_targets
            )
            key_img_terms = bce_sum(_at_least_float32(key_frames_pred), img_targets)
            if reduction == "per_pixel":
                key_img_terms = key_img_terms / img_targets.shape[-1]
            per_key = per_key + beta_ki * key_img_terms
            terms["key_img"] = key_img_terms
        key_loss = (key_weights * per_key).sum(-1)  # (B,)

        inter_loss, mixed, coverage = interpolation_loss(frame_pos, inter_frames_pred, future_frames, lengths, pixel_weights)
        if reduction != "sum":
            per_scalar = future_frames.shape[-1] if reduction == "per_pixel" else 1
            inter_loss = inter_loss / (lengths.to(inter_loss).clamp_min(1) * per_scalar)

        result = {name: (key_weights * term).sum(-1).mean() for name, term in terms.items()}
        result.update(
            loss=(key_loss + inter_loss).mean(),
            key=key_loss.mean(),
            inter=inter_loss.mean(),
            c=in_sequence,
            coverage=coverage,
            soft_frames=mixed,
        )
    return result


def offset_teacher_loss(offset_logits: Tensor, target_offsets: Tensor) -> Tensor:
    """Cross-entropy of the offset distributions to teacher offsets (our addition, not the paper's).

    Args:
        offset_logits: (B, M, S) logits of δ.
        target_offsets: (B, M) offsets in 1…S; ``IGNORE_OFFSET`` (or any value < 1) for none.
    Returns:
        Scalar: mean over the keyframes with a target (0 if none).
    """
    targets = torch.where(target_offsets > 0, target_offsets - 1, torch.full_like(target_offsets, IGNORE_OFFSET))
    if not bool((targets >= 0).any()):
        return offset_logits.sum() * 0.0
    return F.cross_entropy(offset_logits.flatten(0, 1).float(), targets.flatten(), ignore_index=IGNORE_OFFSET)


def boundary_teacher_loss(boundary_scores: Tensor, boundaries: Tensor, lengths: Tensor) -> Tensor:
    """Binary cross-entropy of per-frame boundary scores to teacher boundaries (our addition).

    Args:
        boundary_scores: (B, N) boundary logits.
        boundaries: (B, N) 0/1 targets.
        lengths: (B,) valid future frames; padding gets no label.
    Returns:
        Scalar: mean over the valid frames.
    """
    valid = valid_frame_mask(lengths.to(boundary_scores.device), boundary_scores.shape[1])
    return F.binary_cross_entropy_with_logits(boundary_scores[valid], boundaries.to(boundary_scores)[valid])


@in_float32  # a clamp at 1e-12 is 0 in half precision, and 0 · log 0 is NaN
def offset_entropy(offset_probs: Tensor) -> Tensor:
    """(B, M) entropy in nats of each offset distribution δ (B, M, S), in float32."""
    return -(offset_probs * offset_probs.clamp_min(1e-12).log()).sum(-1)


