"""SVG-FP's recurrent core for the Surprise baseline (REFERENCE §4; Denton & Fergus 2018).

At step t the frame predictor reads ``[enc(I_{t-1}), z_t]`` and emits the embedding of ``I_t``;
the posterior LSTM reads ``enc(I_t)``, so ``q(z_t | I_≤t)``; the prior is a fixed N(0, I). The
encoder and decoder are KEYIN's (:mod:`keyin.models.conv`), sized the same.
"""

from __future__ import annotations

import torch
from torch import Tensor, nn

from keyin.models.recurrent import LSTMBlock


class SVGCore(nn.Module):
    """Posterior LSTM and frame-predictor LSTM of SVG-FP.

    Args:
        embed_dim: E, the encoder's embedding size.
        latent_dim: Z, the per-step latent.
        hidden: hidden size of both LSTMs.
        predictor_layers: layers of the frame predictor (SVG: 2).
        posterior_layers: layers of the posterior (SVG: 1).
    """

    def __init__(
        self, embed_dim: int, latent_dim: int, hidden: int, predictor_layers: int = 2, posterior_layers: int = 1
    ) -> None:
        super().__init__()
        self.latent_dim = latent_dim
        self.posterior = LSTMBlock(embed_dim, 2 * latent_dim, hidden, posterior_layers)
        self.predictor = LSTMBlock(embed_dim + latent_dim, embed_dim, hidden, predictor_layers)

    def posterior_stats(self, embeddings: Tensor) -> tuple[Tensor, Tensor]:
        """``q(z_t | I_≤t)`` at every step.

        Args:
            embeddings: (B, L, E).
        Returns:
            mu, log_sigma: (B, L, Z).
        """
        stats, _ = self.posterior(embeddings)
        mu, log_sigma = stats.chunk(2, dim=-1)
        return mu, log_sigma

    def forward(self, embeddings: Tensor, sample: bool = True) -> tuple[Tensor, Tensor, Tensor]:
        """Teacher-forced one-step predictions of frames 1 … L-1.

        Args:
            embeddings: (B, L, E) encoded clip.
            sample: draw z_t from the posterior; False uses its mean.
        Returns:
            predicted (B, L-1, E) embeddings of frames 1 … L-1 (tanh, like the encoder's), and the
            posterior mu, log_sigma (B, L, Z) of every step.
        """
        mu, log_sigma = self.posterior_stats(embeddings)
        z = mu + log_sigma.exp() * torch.randn_like(mu) if sample else mu
        inputs = torch.cat([embeddings[:, :-1], z[:, 1:]], dim=-1)  # (B, L-1, E + Z)
        predicted, _ = self.predictor(inputs)
        return torch.tanh(predicted), mu, log_sigma
