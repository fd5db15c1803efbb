"""SVG-FP, the Surprise baseline's model (paper App. 9; Denton & Fergus 2018): its recurrent core
and the whole model around it.

At step t the frame predictor reads ``[enc(I_{t-1}), z_t]`` and emits the embedding of ``I_t``;
the posterior LSTM reads ``enc(I_t)``, so ``q(z_t | I_≤t)``; the prior is a fixed N(0, I). The
encoder and decoder are KEYIN's (:mod:`keyin.models.conv`), sized the same.
"""

from __future__ import annotations

from typing import NamedTuple

import torch
from torch import Tensor, nn

from keyin.models.conv import ConvDecoder, ConvEncoder
from keyin.models.distributions import gaussian_kl
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


class SVGOutput(NamedTuple):
    """The teacher-forced pass of :meth:`SVG.forward` over clips of L frames.

    Attributes:
        logits: (B, L-1, C, H, W) one-step predictions of frames 1 … L-1.
        mu, log_sigma: (B, L, Z) the posterior of every step.
        reconstruction: (B, L, C, H, W) logits of every frame decoded from its own embedding, or
            None when not asked for.
    """

    logits: Tensor
    mu: Tensor
    log_sigma: Tensor
    reconstruction: Tensor | None


class SVG(nn.Module):
    """SVG-FP: encoder, :class:`SVGCore` and decoder.

    Args:
        encoder, decoder: KEYIN's; a decoder built with ``skips`` decodes every frame with the
            encoder features of the clip's last conditioning frame (SVG's skip connections), so the
            predictor need not carry the static scene.
        core: the posterior and the frame predictor.
        n_cond: conditioning frames at the start of every clip.
    """

    def __init__(self, encoder: ConvEncoder, decoder: ConvDecoder, core: SVGCore, n_cond: int) -> None:
        super().__init__()
        self.encoder, self.decoder, self.core = encoder, decoder, core
        self.n_cond = n_cond

    def encode(self, clips: Tensor) -> tuple[Tensor, list[Tensor] | None]:
        """(B, L, E) embeddings of (B, L, C, H, W) clips, and the decoder's context: with skips the
        encoder features of each clip's last conditioning frame (B, F·2^i, h_i, h_i), else None."""
        if not self.decoder.skips:
            return self.encoder(clips), None
        embeddings, skips = self.encoder.embed_with_skips(clips)
        return embeddings, [features[:, self.n_cond - 1] for features in skips]

    def decode(self, embeddings: Tensor, context: list[Tensor] | None) -> Tensor:
        """(B, T, C, H, W) logits of (B, T, E) embeddings with the context of :meth:`encode`
        (its batch B or 1, broadcast over B and T)."""
        if context is None:
            return self.decoder(embeddings)
        batch, steps = embeddings.shape[:2]
        return self.decoder(embeddings, [features.unsqueeze(1).expand(batch, steps, -1, -1, -1) for features in context])

    def forward(self, clips: Tensor, sample: bool = True, reconstruct: bool = False) -> SVGOutput:
        """Teacher-forced one-step predictions of (B, L, C, H, W) clips.

        Args:
            sample: draw z_t from the posterior; False uses its mean.
            reconstruct: also decode every frame from its own embedding (the auto-encoding term).
        """
        embeddings, context = self.encode(clips)
        predicted, mu, log_sigma = self.core(embeddings, sample=sample)
        if not reconstruct:
            return SVGOutput(self.decode(predicted, context), mu, log_sigma, None)
        # the predicted and the auto-encoded frames in one decoder batch: a BatchNorm decoder's eval mode then renders
        # what training normalised (keyin.models.conv.decode_in_one_batch)
        both = self.decode(torch.cat([predicted, embeddings], dim=1), context)
        logits, reconstruction = both.split([predicted.shape[1], embeddings.shape[1]], dim=1)
        return SVGOutput(logits, mu, log_sigma, reconstruction)

    def one_step_video(self, clips: Tensor) -> Tensor:
        """(B, L, C, H, W) probabilities: frame 0 of (B, L, C, H, W) clips, then the one-step
        predictions from the posterior mean."""
        return torch.cat([clips[:, :1], torch.sigmoid(self(clips, sample=False).logits)], dim=1)

    @torch.no_grad()
    def surprise(self, clips: Tensor) -> Tensor:
        """(B, L) KL of the posterior to the prior at every step of (B, L, C, H, W) clips (a score
        for discovery and planning: no gradient)."""
        return gaussian_kl(*self.core.posterior_stats(self.encoder(clips)))

    def rollout(self, cond_emb: Tensor, z: Tensor) -> Tensor:
        """The frame predictor rolled out from the prior's latents.

        As in training, step t reads the embedding of frame t - 1 and z_t. The conditioning frames
        are teacher-forced with their posterior means; after them every step reads its own prediction.

        Args:
            cond_emb: (1 or n, n_cond, E) embeddings of the conditioning frames.
            z: (n, T, Z) latents of the T future steps.
        Returns:
            (n, T, E) predicted embeddings of the future frames.
        """
        predictor, n = self.core.predictor, len(z)
        cond_z, _ = self.core.posterior_stats(cond_emb)  # (1 or n, n_cond, Z)
        cond_emb, cond_z = cond_emb.expand(n, -1, -1), cond_z.expand(n, -1, -1)
        inputs = torch.cat([cond_emb[:, :-1], cond_z[:, 1:]], -1)  # (n, n_cond - 1, E + Z)
        state = predictor(inputs)[1] if inputs.shape[1] else None
        previous, predicted = cond_emb[:, -1], []
        for step in range(z.shape[1]):
            output, state = predictor.step(torch.cat([previous, z[:, step]], -1), state)
            previous = torch.tanh(output)
            predicted.append(previous)
        return torch.stack(predicted, 1)
