"""The diagonal Gaussian's KL to the standard normal, shared by KEYIN's keyframe latents, the
interpolator's latent and SVG-FP's per-step latents."""

import torch
from torch import Tensor


def gaussian_kl(mu: Tensor, log_sigma: Tensor) -> Tensor:
    """KL(N(mu, sigma^2) || N(0, I)) summed over the last dimension (paper eq. 3).

    Args:
        mu: (..., Z) means.
        log_sigma: (..., Z) log standard deviations.
    Returns:
        (...) ``Σ_z [-log σ + (σ² + μ²) / 2 - 1/2]``.
    """
    return (-log_sigma + 0.5 * (torch.exp(2 * log_sigma) + mu**2) - 0.5).sum(-1)
