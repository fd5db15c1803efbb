"""Stage 1: the stochastic interpolator with its encoder and decoder (REFERENCE §2.5, §2.7a).

Trains CNN_enc, CNN_dec, MLP_init_inter and LSTM_inter on random segments of clips: the
interpolator sees the two boundary embeddings and the offset and must render the frames between
them; a seq2seq-VAE latent (posterior over the targets, KL to N(0, I)) lets it cope with segments
whose boundaries are not true keyframes. An auto-encoding term keeps the decoder able to render
any embedding (stage 2 never supervises keyframe images, β_ki = 0).
"""

from __future__ import annotations

from typing import Any

import lightning as L
import torch
import torch.nn.functional as F

from keyin.data.segments import all_segments, crosses_keyframe, partition_segments, segment_frames
from keyin.losses.image import model_pixel_weights
from keyin.losses.soft_keyframe import gaussian_kl
from keyin.models import ConvDecoder, ConvEncoder, Interpolator, InterpolatorPosterior


class InterpolatorModule(L.LightningModule):
    """Stage 1 of KEYIN; its encoder, decoder and interpolator are frozen in stage 2."""

    stage = "interpolator"

    def __init__(
        self,
        image_size: int,
        channels: int,
        n_cond: int,
        n_future: int,
        max_offset: int,
        embed_dim: int,
        conv_width: int,
        coord_channels: bool,
        norm: str,
        latent_dim: int,
        lstm_hidden: int,
        lstm_layers: int,
        mlp_hidden: int,
        step_input: str,
        offset_min: int,
        offset_max: int,
        kl_weight: float,
        ae_weight: float,
        lr: float,
        ae_frames: int = 0,
        diagnostic_clips: int = 24,
        foreground_weight: float = 1.0,
        foreground_threshold: float = 0.1,
    ) -> None:
        super().__init__()
        if not 1 <= offset_min <= offset_max <= max_offset:
            raise ValueError(
                f"interpolator offsets [{offset_min}, {offset_max}] must lie in [1, max_offset="
                f"{max_offset}]"
            )
        self.save_hyperparameters()
        conv = dict(
            image_size=image_size,
            channels=channels,
            width=conv_width,
            embed_dim=embed_dim,
            coord_channels=coord_channels,
            norm=norm,
        )
        self.encoder = ConvEncoder(**conv)
        self.decoder = ConvDecoder(**conv)
        self.interpolator = Interpolator(
            embed_dim, max_offset, latent_dim, lstm_hidden, lstm_layers, mlp_hidden, step_input
        )
        self.posterior = InterpolatorPosterior(embed_dim, latent_dim, lstm_hidden) if latent_dim else None
        self.segment_rng = torch.Generator().manual_seed(0)

    def interpolate(
        self,
        embeddings: torch.Tensor,
        clip: torch.Tensor,
        start: torch.Tensor,
        offset: torch.Tensor,
        latent: str,
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Interpolated embeddings of segments.

        Args:
            embeddings: (B, L, E) encoded clips.
            clip, start, offset: (R,) the segments.
            latent: "posterior" (z from the targets), "prior" (z ~ N(0, I)) or "mean" (z = 0).
        Returns:
            predicted (R, S, E), valid (R, S) bool, kl (R,) (zeros unless posterior).
        """
        max_offset = self.hparams.max_offset
        device = embeddings.device
        clip, start, offset = clip.to(device), start.to(device), offset.to(device)
        frames, valid = segment_frames(start, offset, max_offset)
        rows = clip.shape[0]
        kl = torch.zeros(rows, device=device)
        z = torch.zeros(rows, self.hparams.latent_dim, device=device)
        if self.posterior is not None and latent == "posterior":
            mu, log_sigma = self.posterior(embeddings[clip[:, None], frames], valid)
            z = mu + log_sigma.exp() * torch.randn_like(mu)
            kl = gaussian_kl(mu, log_sigma)
        elif latent == "prior":
            z = torch.randn_like(z)
        offset_onehot = F.one_hot(offset - 1, max_offset).float()
        predicted = self.interpolator(
            embeddings[clip, start], embeddings[clip, start + offset], offset_onehot, z
        )
        return predicted, valid, kl

    def pixel_weights(self, clips: torch.Tensor) -> torch.Tensor | None:
        """(B, L, C, H, W) weights of the image likelihood, None for the plain BCE (keyin/losses/image.py)."""
        return model_pixel_weights(clips, self.hparams)

    def _segment_bce(
        self,
        clips: torch.Tensor,
        weights: torch.Tensor | None,
        embeddings: torch.Tensor,
        clip,
        start,
        offset,
        latent: str,
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Per-segment summed BCE of the existing outputs (pixel ``weights`` like ``clips``, or
        None), their count, and the KL."""
        predicted, valid, kl = self.interpolate(embeddings, clip, start, offset, latent)
        frames, _ = segment_frames(start.to(clips.device), offset.to(clips.device), self.hparams.max_offset)
        rows = clip.to(clips.device)[:, None]
        targets = clips[rows, frames][valid]  # (V, C, H, W)
        weights = None if weights is None else weights[rows, frames][valid]
        logits = self.decoder(predicted[valid])
        bce = F.binary_cross_entropy_with_logits(logits, targets, weights, reduction="none").flatten(1).sum(1)
        per_segment = torch.zeros(valid.shape[0], device=clips.device).index_put_(
            (valid.nonzero()[:, 0],), bce, accumulate=True
        )
        return per_segment, valid.sum(1), kl

    def training_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> torch.Tensor:
        clips = batch["frames"]  # (B, L, C, H, W)
        n_clips, clip_length = clips.shape[:2]
        lengths = self.hparams.n_cond + batch["future_length"]  # (B,) valid frames; the rest is padding
        embeddings = self.encoder(clips)  # (B, L, E)
        weights = self.pixel_weights(clips)
        clip, start, offset = partition_segments(
            lengths, self.hparams.offset_min, self.hparams.offset_max, self.segment_rng
        )
        bce, _, kl = self._segment_bce(clips, weights, embeddings, clip, start, offset, "posterior")
        reconstruction = bce.sum() / n_clips
        kl_term = kl.sum() / n_clips
        valid = torch.arange(clip_length, device=clips.device)[None] < lengths.to(clips.device)[:, None]
        autoencoding = self._autoencoding_bce(
            clips[valid], embeddings[valid], None if weights is None else weights[valid]
        ) / n_clips
        loss = reconstruction + self.hparams.kl_weight * kl_term + self.hparams.ae_weight * autoencoding
        self.log_dict(
            {
                "train/loss": loss,
                "train/bce_per_frame": bce.sum() / (offset.sum() + 1e-9),
                "train/kl_per_segment": kl.mean(),
                "train/ae_per_frame": autoencoding * n_clips / valid.sum(),
            },
            prog_bar=True,
        )
        return loss

    def _autoencoding_bce(
        self, frames: torch.Tensor, embeddings: torch.Tensor, weights: torch.Tensor | None
    ) -> torch.Tensor:
        """Summed (pixel-weighted) BCE of decoding the frames' own embeddings, (F, C, H, W) and (F, E).

        With ``ae_frames`` > 0 a uniform random subset of that many frames is decoded and the sum is
        rescaled to all frames (an unbiased estimate at a fraction of the decoder's cost).
        """
        n_frames = frames.shape[0]
        if 0 < self.hparams.ae_frames < n_frames:
            pick = torch.randperm(n_frames, generator=self.segment_rng)[: self.hparams.ae_frames].to(frames.device)
            frames, embeddings = frames[pick], embeddings[pick]
            weights = None if weights is None else weights[pick]
        bce = F.binary_cross_entropy_with_logits(self.decoder(embeddings), frames, weights, reduction="sum")
        return bce * n_frames / frames.shape[0]

    @torch.no_grad()
    def offset_contrast(self, batch: dict[str, torch.Tensor], latent: str = "prior") -> dict[str, Any]:
        """Per-offset BCE per frame on segments with and without a true keyframe inside.

        This is the gate before stage 2 (PROTOTYPE-FINDINGS §4): stage 2 can only find keyframes
        if a segment that crosses a keyframe costs clearly more than a straight one of the same
        offset. Uses the future part of the clips (plus K^0), where keyframes are labelled.
        """
        clips = batch["frames"][: self.hparams.diagnostic_clips]
        n_cond = self.hparams.n_cond
        keyframes = F.pad(batch["keyframes"][: len(clips)], (n_cond, 0))  # on the clip axis
        embeddings = self.encoder(clips)
        weights = self.pixel_weights(clips)
        last = n_cond - 1 + batch["future_length"][: len(clips)].cpu()  # (B,) last valid frame
        table = {}
        for offset in range(1, self.hparams.max_offset + 1):
            clip, start, offs = all_segments(len(clips), n_cond - 1, clips.shape[1] - 1, offset)
            inside = start + offs <= last[clip]  # segments that reach into the padding are left out
            clip, start, offs = clip[inside], start[inside], offs[inside]
            bce, count, _ = self._segment_bce(clips, weights, embeddings, clip, start, offs, latent)
            bent = crosses_keyframe(keyframes.cpu(), clip, start, offs).to(bce.device)
            per_frame = bce / count
            table[offset] = {
                "straight": per_frame[~bent].mean().item() if (~bent).any() else float("nan"),
                "bent": per_frame[bent].mean().item() if bent.any() else float("nan"),
            }
        return table

    def validation_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> None:
        if batch_idx > 0:
            return
        table = self.offset_contrast(batch)
        straight = torch.tensor([row["straight"] for row in table.values()]).nanmean()
        bent = torch.tensor([row["bent"] for row in table.values()]).nanmean()
        self.log_dict(
            {"val/bce_straight": straight, "val/bce_bent": bent, "val/contrast": bent - straight},
            prog_bar=True,
            sync_dist=True,  # under DDP: the mean over the ranks' first batches
        )
        for offset, row in table.items():
            self.log(f"val/bce_straight_o{offset}", row["straight"], sync_dist=True)
            self.log(f"val/bce_bent_o{offset}", row["bent"], sync_dist=True)

    def configure_optimizers(self) -> torch.optim.Optimizer:
        return torch.optim.Adam(self.parameters(), lr=self.hparams.lr, betas=(0.9, 0.999))
