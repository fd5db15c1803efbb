"""Key-value attention posterior over the future frames (paper §3.1, eq. 1-2)."""

import math

import torch
from torch import Tensor


def attention_posterior(
    query: Tensor,
    keys: Tensor,
    values: Tensor,
    mask: Tensor,
    inv_temperature: Tensor | float = 1.0,
    scale: bool = True,
) -> tuple[Tensor, Tensor, Tensor]:
    """Attention-averaged Gaussian parameters of one keyframe's posterior.

    Eq. 1-2: α_j = softmax_j(⟨query, key_j⟩) over the valid frames, [μ, log σ] = Σ_j α_j τ_j — the
    Gaussian parameters themselves (μ and log σ, not σ) are averaged. With `scale`, the scores are
    divided by √E (unscaled E-dim inner products make the softmax peaked from the start;
    docs/architecture.md, "Sizes the paper does not give"); `inv_temperature` always multiplies
    them (pass a learnable scalar, or 1.0 for the paper).

    Masked frames get score −∞. A row with no valid frame would give 0/0 = NaN in the softmax
    (docs/architecture.md, "Padding and masking"); there the weights are all zero and so μ = log σ = 0, i.e. the posterior falls
    back to the prior N(0, I) (a KL of zero), with finite gradients.

    Args:
        query: (B, E), the previous keyframe embedding K̂^{e,t-1}.
        keys: (B, N, E), K^{e,inf}_j.
        values: (B, N, 2Z), τ_j = [μ_j, log σ_j].
        mask: (B, N) bool, True where frame j is valid.
        inv_temperature: scalar (0-dim tensor or float) multiplying the scores.
        scale: divide the scores by √E.
    Returns:
        mu (B, Z), log_sigma (B, Z), weights (B, N): sum to 1 over the valid frames of each row
        (0 on masked frames; all 0 where no frame is valid).
    """
    scores = torch.einsum("be,bne->bn", query, keys) * inv_temperature  # (B, N)
    if scale:
        scores = scores / math.sqrt(query.shape[-1])
    has_valid = mask.any(dim=-1, keepdim=True)  # (B, 1)
    scores = scores.masked_fill(~mask, float("-inf"))
    # A finite dummy row for all-masked rows keeps the softmax (and its gradient) free of NaN;
    # multiplying by has_valid then zeroes those rows.
    scores = torch.where(has_valid, scores, torch.zeros_like(scores))
    weights = torch.softmax(scores, dim=-1) * has_valid  # (B, N)
    gaussian_params = torch.einsum("bn,bnz->bz", weights, values)  # (B, 2Z)
    mu, log_sigma = gaussian_params.chunk(2, dim=-1)  # (B, Z) each
    return mu, log_sigma, weights
