"""The Surprise baseline: SVG-FP trained on whole clips, keyframes at peaks of its KL (paper §4.1.2, App. 9).

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

from keyin.data.segments import valid_frames
from keyin.decode.surprise import surprise_keyframes
from keyin.eval.f1 import discovery_summary, keyframe_lists
from keyin.legacy import upgrade_state_dict
from keyin.models.modes import evaluating
from keyin.losses.image import model_pixel_weights
from keyin.losses.svg import SVGTerms, kl_reveal_ratio, kl_schedule, svg_loss, svg_terms
from keyin.models import SVG, ConvDecoder, ConvEncoder, SVGCore
from keyin.lit.optimizers import adam


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
        skips: SVG's skip connections (:class:`keyin.models.SVG`; False: KEYIN's decoder, no skips).
    """

    stage = "surprise"
    monitor = ("val/f1", "max")  # best.ckpt: keyframe F1 on the validation clips

    def __init__(
        self, image_size: int, channels: int, n_cond: int, n_future: int, n_keyframes: int, embed_dim: int,
        conv_width: int, coord_channels: bool, norm: str, latent_dim: int, lstm_hidden: int, predictor_layers: int,
        posterior_layers: int, beta: float, lr: float, shift: int = -1, ae_weight: float = 0.0, beta_warmup: int = 0,
        beta_delay: int = 0, foreground_weight: float = 1.0, foreground_threshold: float = 0.1, skips: bool = False,
    ) -> None:
        super().__init__()
        self.save_hyperparameters(logger=False)  # the trackers get the whole run config (keyin.cli.tracking)
        conv = dict(
            image_size=image_size, channels=channels, width=conv_width, embed_dim=embed_dim,
            coord_channels=coord_channels, norm=norm,
        )
        encoder, decoder = ConvEncoder(**conv), ConvDecoder(**conv, skips=skips)  # in this order: the seed's draws
        core = SVGCore(embed_dim, latent_dim, lstm_hidden, predictor_layers, posterior_layers)
        self.model = SVG(encoder, decoder, core, n_cond)

    def on_load_checkpoint(self, checkpoint: dict[str, Any]) -> None:
        # Checkpoints from before the SVG model keep its networks at the top level (encoder.*, core.*, ...).
        checkpoint["state_dict"] = upgrade_state_dict(checkpoint["state_dict"], self.stage)

    def _terms(self, batch: dict[str, torch.Tensor], sample: bool = True) -> SVGTerms:
        """The loss terms of a batch; ``sample`` False predicts from the posterior mean (validation)."""
        clips = batch["frames"]
        out = self.model(clips, sample=sample, reconstruct=self.hparams.ae_weight > 0)
        valid = valid_frames(self.hparams.n_cond + batch["future_length"].to(clips.device), clips.shape[1])
        return svg_terms(*out, clips, valid, model_pixel_weights(clips, self.hparams))

    def _shared_step(self, batch: dict[str, torch.Tensor], stage: str) -> tuple[torch.Tensor, SVGTerms]:
        """The loss of a batch and its terms, logged with the KL weight (warming up in training)."""
        terms = self._terms(batch, sample=stage == "train")
        hp = self.hparams
        beta = kl_schedule(self.global_step, hp.beta, hp.beta_warmup, hp.beta_delay) if stage == "train" else hp.beta
        loss, n_steps = svg_loss(terms, beta, hp.ae_weight), terms.valid.sum()
        self.log_dict(
            {
                f"{stage}/loss": loss,
                f"{stage}/bce_per_frame": terms.bce.sum() / n_steps,
                f"{stage}/kl_per_step": terms.kl.sum() / n_steps,  # → 0 is the KL collapse to watch for
                f"{stage}/kl_weight": beta,
            },
            prog_bar=stage == "train",
            sync_dist=stage == "val",  # under DDP: the mean over every rank's clips
        )
        return loss, terms

    def training_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> torch.Tensor:
        return self._shared_step(batch, "train")[0]

    def validation_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> None:
        _, terms = self._shared_step(batch, "val")
        ratio = kl_reveal_ratio(terms.kl, terms.valid, batch["keyframes"], self.hparams.n_cond)
        self.log("val/kl_reveal_ratio", ratio, sync_dist=True)
        summary = discovery_summary(self.discover(batch["frames"], batch["future_length"]), batch["keyframes"])
        self.log_dict({f"val/{key}": value for key, value in summary.items()}, prog_bar=True, sync_dist=True)

    @torch.no_grad()
    def discover(self, clips: torch.Tensor, future_length: torch.Tensor, shift: int | None = None) -> list[list[int]]:
        """Keyframe positions: the M largest KL peaks, shifted by ``shift`` (default: the module's)."""
        with evaluating(self):
            kl = self.model.surprise(clips.to(self.device)).cpu()
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
        clips, lengths = batch["frames"][:count].to(self.device), batch["future_length"][:count]
        with evaluating(self):
            predicted = self.model.one_step_video(clips)
            valid = valid_frames(self.hparams.n_cond + lengths.to(self.device), clips.shape[1])
            kl = self.model.surprise(clips).masked_fill(~valid, float("nan")).cpu()
        truth = keyframe_lists(batch["keyframes"][:count])
        discovered = self.discover(clips, lengths)
        videos = [clips, predicted]
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
        """The method as configured, and the other index reading (docs/architecture.md, "Baselines")."""
        other = 0 if self.hparams.shift != 0 else -1
        return {name: self.discover, f"{name}_shift{other}": functools.partial(self.discover, shift=other)}

    def configure_optimizers(self) -> torch.optim.Optimizer:
        return adam(self, self.hparams.lr)
