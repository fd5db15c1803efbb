"""Stage 1: the stochastic interpolator with its encoder and decoder (paper §3.2 "Training procedure", §4).

Trains CNN_enc, CNN_dec, MLP_init_inter and LSTM_inter on random segments of clips: the
interpolator sees the two boundary embeddings and the offset and must render the frames between
them; a seq2seq-VAE latent (posterior over the targets, KL to N(0, I)) lets it cope with segments
whose boundaries are not true keyframes. An auto-encoding term keeps the decoder able to render
any embedding (stage 2 never supervises keyframe images, β_ki = 0).

With ``frozen_frames`` (``backbone=frames``, issue 25) the encoder and decoder are a frame
autoencoder's (:meth:`InterpolatorModule.load_frame_model`), frozen from the first step: stage 1
trains the interpolator (and its posterior) alone, through the fixed decoder, and has no
auto-encoding term.
"""

from __future__ import annotations

import lightning as L
import torch
import torch.nn.functional as F

from keyin.data.segments import partition_segments, valid_frames
from keyin.errors import CheckpointError
from keyin.losses.image import model_pixel_weights
from keyin.losses.interpolation import (
    autoencoding_bce, autoencoding_pick, interpolated_outputs, interpolation_bce, offset_contrast, segment_bce,
)
from keyin.models import InterpolatorPosterior
from keyin.models.config import FrameModelConfig, InterpolatorConfig, picked
from keyin.models.conv import decode_in_one_batch
from keyin.models.distributions import gaussian_kl
from keyin.models.keyin import stage1_networks
from keyin.lit.optimizers import adam
from keyin.models.state import sub_state_dict


class InterpolatorModule(L.LightningModule):
    """Stage 1 of KEYIN; its encoder, decoder and interpolator are frozen in stage 2."""

    stage = "interpolator"
    monitor = ("val/bce_per_frame", "min")  # best.ckpt: interpolation error of every validation segment

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
        frozen_frames: bool = False,
    ) -> None:
        super().__init__()
        if not 1 <= offset_min <= offset_max <= max_offset:
            raise ValueError(f"interpolator offsets [{offset_min}, {offset_max}] must lie in [1, max_offset={max_offset}]")
        self.save_hyperparameters(logger=False)  # the trackers get the whole run config (keyin.cli.tracking)
        self.encoder, self.decoder, self.interpolator = stage1_networks(
            picked(FrameModelConfig, self.hparams), picked(InterpolatorConfig, self.hparams), max_offset
        )
        self.posterior = InterpolatorPosterior(embed_dim, latent_dim, lstm_hidden) if latent_dim else None
        self.segment_rng = torch.Generator().manual_seed(0)
        if frozen_frames:
            self.freeze_frame_model()

    def on_fit_start(self) -> None:
        """Under DDP, rank r draws its segments from seed r (one process: 0, as always)."""
        self.segment_rng.manual_seed(self.global_rank)

    @property
    def frozen_by_design(self) -> str | None:
        """What stays frozen in eval mode while this stage trains (said once by keyin.lit.run), or None."""
        return "stage 1: the frame autoencoder's encoder and decoder (backbone=frames)" if self.hparams.frozen_frames else None

    def freeze_frame_model(self) -> None:
        """No gradients into the encoder and decoder, and eval mode for them (``frozen_frames``)."""
        for network in (self.encoder, self.decoder):
            network.requires_grad_(False).eval()

    def train(self, mode: bool = True) -> "InterpolatorModule":
        """Switch the trainable parts; a frozen frame model stays in eval mode."""
        super().train(mode)
        if self.hparams.frozen_frames:
            self.freeze_frame_model()
        return self

    def load_frame_model(self, checkpoint: dict, source: str) -> None:
        """Copy the encoder and decoder of a frame autoencoder's checkpoint (``source`` names it in
        errors); its sizes must be this stage 1's."""
        saved = checkpoint["hyper_parameters"]
        sizes = ("image_size", "channels", "embed_dim", "conv_width", "coord_channels", "norm")
        differ = [f"{key}={saved.get(key)!r} (stage 1: {self.hparams[key]!r})" for key in sizes if saved.get(key) != self.hparams[key]]
        if differ:
            raise CheckpointError(
                f"the frame autoencoder {source} is not this stage 1's frame model: {', '.join(differ)}; train one with "
                f"this dataset=, scale= and backbone=ours (keyin-train model=frame_autoencoder ...), or set this "
                f"stage 1's sizes to the autoencoder's"
            )
        for name in ("encoder", "decoder"):
            getattr(self, name).load_state_dict(sub_state_dict(checkpoint["state_dict"], f"network.{name}."))

    def segment_bce(
        self,
        clips: torch.Tensor,
        weights: torch.Tensor | None,
        embeddings: torch.Tensor,
        segments: tuple[torch.Tensor, torch.Tensor, torch.Tensor],
        latent: str,
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Per-segment summed BCE (R,) of the interpolated frames of ``segments`` (clip, start,
        offset, each (R,)), their frame count (R,) and the KL (R,) (zeros unless ``latent`` is
        "posterior" and the interpolator stochastic)."""
        bce, count, posterior = interpolation_bce(
            self.interpolator, self.posterior, self.decoder, embeddings, clips, weights, segments, latent
        )
        kl = gaussian_kl(*posterior) if posterior is not None else torch.zeros_like(bce)
        return bce, count, kl

    def pixel_weights(self, clips: torch.Tensor) -> torch.Tensor | None:
        """(B, L, C, H, W) weights of the image likelihood, None for the plain BCE (keyin/losses/image.py)."""
        return model_pixel_weights(clips, self.hparams)

    def autoencoded_frames(
        self, clips: torch.Tensor, embeddings: torch.Tensor, weights: torch.Tensor | None, lengths: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor | None, int]:
        """The frames the auto-encoding term decodes, (F', C, H, W): ``ae_frames`` drawn at random among the (B, L, C, H, W)
        clips' valid ones (all for 0), with their embeddings (F', E) and pixel weights (F', C, H, W) or None, and how many
        valid frames they were drawn from."""
        in_clip = valid_frames(lengths.to(clips.device), clips.shape[1])  # (B, L)
        frames, frame_emb = clips[in_clip], embeddings[in_clip]
        frame_weights = None if weights is None else weights[in_clip]
        pick = autoencoding_pick(len(frames), self.hparams.ae_frames, self.segment_rng)
        if pick is None:
            return frames, frame_emb, frame_weights, len(frames)
        pick = pick.to(clips.device)
        return frames[pick], frame_emb[pick], None if frame_weights is None else frame_weights[pick], len(frames)

    def training_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> torch.Tensor:
        clips = batch["frames"]  # (B, L, C, H, W)
        hp, n_clips = self.hparams, clips.shape[0]
        lengths = hp.n_cond + batch["future_length"]  # (B,) valid frames; the rest is padding
        with torch.set_grad_enabled(not hp.frozen_frames):
            embeddings = self.encoder(clips)  # (B, L, E)
        weights = self.pixel_weights(clips)
        segments = partition_segments(lengths, hp.offset_min, hp.offset_max, self.segment_rng)
        predicted, valid, positions, posterior = interpolated_outputs(
            self.interpolator, self.posterior, embeddings, segments, "posterior"
        )
        # a frozen frame model has learnt to auto-encode already
        autoencoded = None if hp.frozen_frames else self.autoencoded_frames(clips, embeddings, weights, lengths)
        # one decoder batch for the interpolated and the auto-encoded frames (BatchNorm: docs/decisions.md)
        logits, *frame_logits = decode_in_one_batch(
            self.decoder, predicted[valid], *([] if autoencoded is None else [autoencoded[1]])
        )
        bce = segment_bce(logits, valid, clips, weights, segments[0].to(clips.device), positions)
        kl = gaussian_kl(*posterior) if posterior is not None else torch.zeros_like(bce)
        loss = bce.sum() / n_clips + hp.kl_weight * (kl.sum() / n_clips)
        logged = {"train/bce_per_frame": bce.sum() / (segments[2].sum() + 1e-9), "train/kl_per_segment": kl.mean()}
        if autoencoded is not None:
            frames, _, frame_weights, n_frames = autoencoded
            autoencoding = autoencoding_bce(frame_logits[0], frames, frame_weights, n_frames)
            loss = loss + hp.ae_weight * (autoencoding / n_clips)
            logged["train/ae_per_frame"] = autoencoding / n_frames
        self.log_dict({"train/loss": loss, **logged}, prog_bar=True)
        return loss

    @torch.no_grad()
    def offset_contrast(self, batch: dict[str, torch.Tensor], latent: str = "prior") -> dict[int, dict[str, float]]:
        """Per-offset BCE per frame of segments with and without a true keyframe inside, on the
        first ``diagnostic_clips`` clips (:func:`keyin.losses.interpolation.offset_contrast`): stage 2
        can only find keyframes if a bent segment costs clearly more than a straight one."""
        clips = batch["frames"][: self.hparams.diagnostic_clips]
        n_cond = self.hparams.n_cond
        embeddings, weights = self.encoder(clips), self.pixel_weights(clips)

        def score(*segments: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            return self.segment_bce(clips, weights, embeddings, segments, latent)[:2]

        keyframes = F.pad(batch["keyframes"][: len(clips)], (n_cond, 0))  # on the clip axis
        last = n_cond - 1 + batch["future_length"][: len(clips)].cpu()  # (B,) last valid frame
        return offset_contrast(score, keyframes, last, n_cond - 1, self.hparams.max_offset)

    def validation_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> None:
        if batch_idx > 0:
            return
        table = self.offset_contrast(batch)
        # on the module's device: DDP's reduction (NCCL) refuses CPU tensors
        straight = torch.tensor([row["straight"] for row in table.values()], device=self.device).nanmean()
        bent = torch.tensor([row["bent"] for row in table.values()], device=self.device).nanmean()
        every = torch.tensor([row["all"] for row in table.values()], device=self.device).nanmean()  # the stage's validation loss
        self.log_dict(
            {"val/bce_per_frame": every, "val/bce_straight": straight, "val/bce_bent": bent, "val/contrast": bent - straight},
            prog_bar=True,
            sync_dist=True,  # under DDP: the mean over the ranks' first batches
        )
        for offset, row in table.items():
            self.log(f"val/bce_straight_o{offset}", row["straight"], sync_dist=True)
            self.log(f"val/bce_bent_o{offset}", row["bent"], sync_dist=True)

    def configure_optimizers(self) -> torch.optim.Optimizer:
        return adam(self, self.hparams.lr)
