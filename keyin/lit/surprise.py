"""The Surprise baseline: SVG-FP trained on whole clips, keyframes at peaks of its KL (REFERENCE §4).

One stage: encoder, decoder and the SVG core learn to predict every frame from the one before and
a latent from the posterior ``q(z_t | I_≤t)``, with a KL to the fixed prior N(0, I). Where the
next frame is unpredictable (the ball turns) the posterior has to carry information, so its KL
peaks; :mod:`keyin.decode.surprise` turns the peaks into keyframes.
"""

from __future__ import annotations

import functools
from typing import Any, Callable

import lightning as L
import torch
import torch.nn.functional as F

from keyin.decode.surprise import surprise_keyframes
from keyin.eval.f1 import discovery_summary, keyframe_lists
from keyin.losses.image import model_pixel_weights
from keyin.losses.soft_keyframe import gaussian_kl
from keyin.models import ConvDecoder, ConvEncoder, SVGCore


def kl_schedule(step: int, beta: float, warmup: int, delay: int) -> float:
    """KL weight at ``step``: 0 for ``delay`` steps, then rising linearly to ``beta`` over ``warmup``."""
    if step < delay:
        return 0.0
    return beta * (min(1.0, (step - delay) / warmup) if warmup > 0 else 1.0)


class SurpriseModule(L.LightningModule):
    """SVG-FP with KEYIN's encoder/decoder sizes; ``discover`` picks the M largest KL peaks.

    Args:
        n_keyframes: M, keyframes per clip.
        latent_dim: Z of the per-step latent.
        beta: weight of the KL (sums over pixels and latent dims, like KEYIN's losses).
        ae_weight: weight of an auto-encoding BCE of every valid frame (as in KEYIN's stage 1);
            without it the decoder learns to draw the ball only slowly, and while the predictions
            are blurry the posterior has nothing to add (docs/baselines.md). 0: SVG-FP's loss.
        shift: added to a peak's future index (-1: the frame before the one that reveals the turn).
        beta_warmup: steps over which the KL weight rises linearly from 0 to ``beta`` (0: none).
            Starting at ``beta`` the posterior collapses before the predictor can use it
            (docs/baselines.md); a warm-up lets it carry information first.
        beta_delay: steps at KL weight 0 before the warm-up starts (the decoder learns to draw
            first; even a small weight can collapse the posterior while it cannot).
        foreground_weight, foreground_threshold: the image likelihood's weight of changed pixels,
            as in KEYIN's stage 1 (keyin/losses/image.py; 1: plain BCE).
        skips: SVG's skip connections: every frame is decoded with the encoder features of the
            clip's last conditioning frame, so the predictor need not carry the static scene
            (False: KEYIN's decoder, no skips).
    """

    stage = "surprise"

    def __init__(
        self,
        image_size: int,
        channels: int,
        n_cond: int,
        n_future: int,
        n_keyframes: int,
        embed_dim: int,
        conv_width: int,
        coord_channels: bool,
        norm: str,
        latent_dim: int,
        lstm_hidden: int,
        predictor_layers: int,
        posterior_layers: int,
        beta: float,
        lr: float,
        shift: int = -1,
        ae_weight: float = 0.0,
        beta_warmup: int = 0,
        beta_delay: int = 0,
        foreground_weight: float = 1.0,
        foreground_threshold: float = 0.1,
        skips: bool = False,
    ) -> None:
        super().__init__()
        self.save_hyperparameters()
        conv = dict(
            image_size=image_size, channels=channels, width=conv_width, embed_dim=embed_dim,
            coord_channels=coord_channels, norm=norm,
        )
        self.encoder = ConvEncoder(**conv)
        self.decoder = ConvDecoder(**conv, skips=skips)
        self.core = SVGCore(embed_dim, latent_dim, lstm_hidden, predictor_layers, posterior_layers)

    def _valid(self, clips: torch.Tensor, future_length: torch.Tensor) -> torch.Tensor:
        """(B, L) True for the conditioning frames and the valid future frames."""
        steps = torch.arange(clips.shape[1], device=clips.device)
        return steps[None] < self.hparams.n_cond + future_length.to(clips.device)[:, None]

    def encode(self, clips: torch.Tensor) -> tuple[torch.Tensor, list[torch.Tensor] | None]:
        """(B, L, E) embeddings of (B, L, C, H, W) clips, and the decoder's context: with skips the
        encoder features of each clip's last conditioning frame (B, F·2^i, h_i, h_i), else None."""
        if not self.hparams.skips:
            return self.encoder(clips), None
        embeddings, skips = self.encoder.embed_with_skips(clips)
        return embeddings, [features[:, self.hparams.n_cond - 1] for features in skips]

    def decode(self, embeddings: torch.Tensor, context: list[torch.Tensor] | None) -> torch.Tensor:
        """(B, T, C, H, W) logits of (B, T, E) embeddings with the context of :meth:`encode`
        (its batch B or 1, broadcast over B and T)."""
        if context is None:
            return self.decoder(embeddings)
        batch, steps = embeddings.shape[:2]
        return self.decoder(embeddings, [features.unsqueeze(1).expand(batch, steps, -1, -1, -1) for features in context])

    def _terms(
        self, batch: dict[str, torch.Tensor], sample: bool = True
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor, torch.Tensor]:
        """Per-step prediction BCE and KL of frames 1 … L-1 (B, L-1), zero on padding, the valid
        mask (B, L-1), and the summed auto-encoding BCE of the valid frames (scalar). ``sample``
        False predicts from the posterior mean (deterministic: validation)."""
        clips = batch["frames"]
        valid_all = self._valid(clips, batch["future_length"])
        valid = valid_all[:, 1:]
        embeddings, context = self.encode(clips)
        predicted, mu, log_sigma = self.core(embeddings, sample=sample)
        weights = model_pixel_weights(clips, self.hparams)
        logits = self.decode(predicted, context)
        bce = F.binary_cross_entropy_with_logits(
            logits, clips[:, 1:], None if weights is None else weights[:, 1:], reduction="none"
        ).flatten(2).sum(-1)
        kl = gaussian_kl(mu[:, 1:], log_sigma[:, 1:])
        autoencoding = clips.new_zeros(())
        if self.hparams.ae_weight > 0:
            autoencoding = F.binary_cross_entropy_with_logits(
                self.decode(embeddings, context)[valid_all], clips[valid_all],
                None if weights is None else weights[valid_all], reduction="sum",
            )
        return bce * valid, kl * valid, valid, autoencoding

    def kl_weight(self) -> float:
        """The KL weight at the current training step (:func:`kl_schedule`)."""
        hp = self.hparams
        return kl_schedule(self.global_step, hp.beta, hp.beta_warmup, hp.beta_delay)

    def _log_terms(
        self, stage: str, bce: torch.Tensor, kl: torch.Tensor, valid: torch.Tensor, autoencoding: torch.Tensor
    ) -> torch.Tensor:
        beta = self.kl_weight() if stage == "train" else self.hparams.beta
        loss = (bce.sum() + beta * kl.sum() + self.hparams.ae_weight * autoencoding) / bce.shape[0]
        n_steps = valid.sum()
        self.log_dict(
            {
                f"{stage}/loss": loss,
                f"{stage}/bce_per_frame": bce.sum() / n_steps,
                f"{stage}/kl_per_step": kl.sum() / n_steps,  # → 0 is the KL collapse to watch for
                f"{stage}/kl_weight": beta,
            },
            prog_bar=stage == "train",
            sync_dist=stage == "val",  # under DDP: the mean over every rank's clips
        )
        return loss

    def training_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> torch.Tensor:
        return self._log_terms("train", *self._terms(batch))

    def validation_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> None:
        bce, kl, valid, autoencoding = self._terms(batch, sample=False)
        self._log_terms("val", bce, kl, valid, autoencoding)
        # Is the KL where the turns are? Mean KL at the frames after a vertex over that elsewhere.
        n_cond = self.hparams.n_cond
        reveals = F.pad(batch["keyframes"], (n_cond, 0))[:, :-1].bool()  # (B, L-1): step t+1 after vertex t
        future_kl = kl.masked_fill(~valid, float("nan"))
        future_kl[:, : n_cond - 1] = float("nan")  # the conditioning frames have no labels
        ratio = future_kl[reveals].nanmean() / future_kl[~reveals].nanmean().clamp_min(1e-9)
        self.log("val/kl_reveal_ratio", ratio, sync_dist=True)
        predicted = self.discover(batch["frames"], batch["future_length"])
        summary = discovery_summary(predicted, batch["keyframes"])
        self.log_dict({f"val/{key}": value for key, value in summary.items()}, prog_bar=True, sync_dist=True)

    @torch.no_grad()
    def surprise(self, clips: torch.Tensor) -> torch.Tensor:
        """(B, L) KL of the posterior to the prior at every step of (B, L, C, H, W) clips."""
        mu, log_sigma = self.core.posterior_stats(self.encoder(clips.to(self.device)))
        return gaussian_kl(mu, log_sigma)

    @torch.no_grad()
    def discover(self, clips: torch.Tensor, future_length: torch.Tensor, shift: int | None = None) -> list[list[int]]:
        """Keyframe positions: the M largest KL peaks, shifted by ``shift`` (default: the module's)."""
        was_training = self.training
        self.eval()
        kl = self.surprise(clips).cpu()
        self.train(was_training)
        shift = self.hparams.shift if shift is None else shift
        return surprise_keyframes(kl, future_length.cpu(), self.hparams.n_cond, self.hparams.n_keyframes, shift)

    @torch.no_grad()
    def validation_pictures(self, batch: dict[str, torch.Tensor], count: int) -> dict[str, Any]:
        """What the validation pictures show for the first ``count`` clips of a batch.

        Returns:
            ``clips`` (2·count, L, C, H, W): per clip the ground truth and the one-step predictions
            from the posterior mean (frame 0 is the given first frame); ``n_cond``; ``truth`` /
            ``predicted``: the true and the surprise keyframes, marked on both rows;
            ``surprise`` (count, L) the KL per step (NaN on padding) with ``surprise_truth`` /
            ``surprise_predicted`` for the KL curves.
        """
        was_training = self.training
        self.eval()
        clips, lengths = batch["frames"][:count].to(self.device), batch["future_length"][:count]
        embeddings, context = self.encode(clips)
        predicted, _, _ = self.core(embeddings, sample=False)
        frames = torch.sigmoid(self.decode(predicted, context))
        kl = self.surprise(clips).masked_fill(~self._valid(clips, lengths), float("nan")).cpu()
        self.train(was_training)
        truth = keyframe_lists(batch["keyframes"][:count])
        discovered = self.discover(clips, lengths)
        videos = [clips, torch.cat([clips[:, :1], frames], dim=1)]
        return {
            "clips": torch.stack(videos, dim=1).flatten(0, 1).cpu(),
            "n_cond": self.hparams.n_cond,
            "truth": [marks for marks in truth for _ in videos],
            "predicted": [marks for marks in discovered for _ in videos],
            "surprise": kl,
            "surprise_truth": truth,
            "surprise_predicted": discovered,
        }

    def discoverers(self, name: str) -> dict[str, Callable]:
        """The method as configured, and the other index reading REFERENCE §4 asks to report."""
        other = 0 if self.hparams.shift != 0 else -1
        return {name: self.discover, f"{name}_shift{other}": functools.partial(self.discover, shift=other)}

    def configure_optimizers(self) -> torch.optim.Optimizer:
        return torch.optim.Adam(self.parameters(), lr=self.hparams.lr, betas=(0.9, 0.999))
