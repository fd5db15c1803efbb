"""Stage 2: the keyframe predictor trained through the frozen interpolator (REFERENCE §2.4, §2.7-2.8).

The encoder, decoder and interpolator of stage 1 are frozen (``requires_grad=False`` and
``.eval()``, re-asserted at every epoch and batch start) but gradients flow *through* them into
the keyframe predictor: LSTM_cond, LSTM_inf with the attention posterior, and LSTM_key with its
keyframe-embedding and offset heads. The loss is the soft keyframe loss (eq. 3-5).
"""

from __future__ import annotations

import functools
from typing import Any, Callable

import lightning as L
import torch

from keyin.decode.rules import KEYIN_RULES, keyin_keyframes
from keyin.decode.teacher import segmentation_targets
from keyin.eval.f1 import discovery_summary, keyframe_lists
from keyin.lit.checkpoints import upgrade_state_dict
from keyin.lit.interpolator import InterpolatorModule
from keyin.losses.image import future_pixel_weights, model_pixel_weights
from keyin.losses.soft_keyframe import (
    argmax_positions,
    boundary_teacher_loss,
    gaussian_kl,
    keyin_loss,
    offset_entropy,
    offset_teacher_loss,
)
from keyin.models import KEYIN, KeyframePredictor

FROZEN = ("encoder", "decoder", "interpolator")


class KeyframeModule(L.LightningModule):
    """Stage 2 of KEYIN (and of the Jumpy / Static baselines through ``offset_mode``)."""

    stage = "keyframes"

    def __init__(
        self,
        stage1: dict[str, Any],
        n_keyframes: int,
        latent_dim: int,
        lstm_hidden: int,
        lstm_layers: int,
        attn_scale: bool,
        offset_mode: str,
        fixed_offset: int | None,
        beta_ke: float,
        beta_ki: float,
        beta_kl: float,
        normalize_key_targets: bool,
        lr: float,
        teacher_weight: float = 0.0,
        teacher_clips: int = 0,
        offset_evidence: bool = False,
        discovery: str = "offsets",
        teacher_keyframe_cost: float = 0.0,
        map_keyframe_cost: float = 120.0,
        map_boundary_weight: float = 10.0,
    ) -> None:
        super().__init__()
        if discovery not in KEYIN_RULES:
            raise ValueError(f"discovery must be one of {KEYIN_RULES}, got {discovery!r}")
        if discovery == "boundaries" and not offset_evidence:
            raise ValueError("discovery='boundaries' needs offset_evidence (the boundary scores)")
        self.save_hyperparameters()
        frozen = InterpolatorModule(**stage1)
        predictor = KeyframePredictor(
            embed_dim=stage1["embed_dim"],
            n_keyframes=n_keyframes,
            max_offset=stage1["max_offset"],
            latent_dim=latent_dim,
            hidden=lstm_hidden,
            layers=lstm_layers,
            attn_scale=attn_scale,
            offset_mode=offset_mode,
            fixed_offset=fixed_offset,
            offset_evidence=offset_evidence,
        )
        self.model = KEYIN(frozen.encoder, frozen.decoder, frozen.interpolator, predictor, stage1["n_cond"])
        self.freeze_stage1()

    def pixel_weights(self, clips: torch.Tensor) -> torch.Tensor | None:
        """(B, L, C, H, W) weights of the image likelihood stage 1 was trained with, or None."""
        return model_pixel_weights(clips, self.hparams.stage1)

    def load_stage1(self, state_dict: dict[str, torch.Tensor]) -> None:
        """Copy the frozen modules' weights from a stage-1 checkpoint's state dict."""
        for name in FROZEN:
            prefix = f"{name}."
            part = {k[len(prefix) :]: v for k, v in state_dict.items() if k.startswith(prefix)}
            getattr(self.model, name).load_state_dict(part)

    def freeze_stage1(self) -> None:
        for name in FROZEN:
            module = getattr(self.model, name)
            module.requires_grad_(False)
            module.eval()

    def on_load_checkpoint(self, checkpoint: dict[str, Any]) -> None:
        # A keyin 0.1 checkpoint keeps the networks at the top level (encoder.*, predictor.*, ...).
        checkpoint["state_dict"] = upgrade_state_dict(checkpoint["state_dict"], self.stage)

    def on_train_epoch_start(self) -> None:
        self.freeze_stage1()

    def on_train_batch_start(self, batch: Any, batch_idx: int) -> None:
        # Lightning puts every module back in train mode after validation (REFERENCE §8.1).
        self.freeze_stage1()

    def _shared_step(self, batch: dict[str, torch.Tensor], stage: str) -> dict[str, torch.Tensor]:
        clips, future_length = batch["frames"], batch["future_length"]
        n_cond = self.model.n_cond
        out = self.model(clips, future_length)
        weights = future_pixel_weights(self.pixel_weights(clips), n_cond)
        terms = keyin_loss(
            offset_probs=out["offset_probs"],
            key_emb_pred=out["key_emb"],
            future_emb=out["future_emb"],
            inter_frames_pred=out["frames"],
            future_frames=clips[:, n_cond:].flatten(2),
            kl_per_key=gaussian_kl(out["mu"], out["log_sigma"]),
            lengths=future_length,
            beta_ke=self.hparams.beta_ke,
            beta_ki=self.hparams.beta_ki,
            beta_kl=self.hparams.beta_kl,
            normalize_key_targets=self.hparams.normalize_key_targets,
            pixel_weights=weights,
        )
        if stage == "train" and self.hparams.teacher_weight > 0:
            teacher = self._teacher_loss(out, future_length)
            terms["teacher"] = teacher
            terms["loss"] = terms["loss"] + self.hparams.teacher_weight * teacher
            self.log("train/teacher", teacher)
        entropy = offset_entropy(out["offset_probs"])
        self.log_dict(
            {
                f"{stage}/loss": terms["loss"],
                f"{stage}/inter": terms["inter"].mean(),
                f"{stage}/key_emb": terms["key_emb"].mean(),
                f"{stage}/kl": terms["kl"].mean(),
                f"{stage}/offset_entropy": entropy.mean(),
                f"{stage}/n_inside": terms["c"].sum(-1).mean(),
                f"{stage}/coverage_end": terms["coverage"][:, -1].mean(),
            },
            prog_bar=stage == "train",
            sync_dist=stage == "val",  # under DDP: the mean over every rank's clips
        )
        return terms

    def _teacher_loss(self, out: dict[str, torch.Tensor], future_length: torch.Tensor) -> torch.Tensor:
        """Cross-entropy of δ (and, with offset evidence, of the boundary scores) to the exact best
        segmentation under the frozen interpolator (:mod:`keyin.decode.teacher`), on the first
        ``teacher_clips`` clips (0: all). Off in the paper's setting; it keeps δ from collapsing to
        one offset for every clip (docs/decisions.md)."""
        n_clips = self.hparams.teacher_clips or out["boundary_emb"].shape[0]
        lengths = future_length[:n_clips]
        offsets, boundaries = segmentation_targets(
            self.model.interpolator, out["boundary_emb"][:n_clips].detach(), lengths, self.hparams.n_keyframes,
            self.hparams.teacher_keyframe_cost,
        )
        loss = offset_teacher_loss(out["offset_logits"][:n_clips], offsets)
        if out["boundary_scores"] is not None:
            loss = loss + boundary_teacher_loss(out["boundary_scores"][:n_clips], boundaries, lengths)
        return loss

    def training_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> torch.Tensor:
        return self._shared_step(batch, "train")["loss"]

    def validation_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> None:
        self._shared_step(batch, "val")
        for name, find in self.discoverers("").items():
            summary = discovery_summary(find(batch["frames"], batch["future_length"]), batch["keyframes"])
            self.log_dict({f"val/{key}{name}": value for key, value in summary.items()}, prog_bar=not name, sync_dist=True)

    @torch.no_grad()
    def discover(
        self, clips: torch.Tensor, future_length: torch.Tensor, discovery: str | None = None
    ) -> list[list[int]]:
        """Keyframe positions by a rule of :func:`keyin.decode.rules.keyin_keyframes` ("offsets",
        "boundaries" or "map"; default: the module's ``discovery``), inside each clip."""
        was_training = self.training
        self.eval()
        clips = clips.to(self.device)
        positions = keyin_keyframes(
            self.model, clips, future_length.to(self.device), discovery or self.hparams.discovery,
            self.hparams.map_keyframe_cost, self.hparams.map_boundary_weight,
            future_pixel_weights(self.pixel_weights(clips), self.model.n_cond),
        )
        self.train(was_training)
        self.freeze_stage1()
        return positions

    @torch.no_grad()
    def validation_pictures(self, batch: dict[str, torch.Tensor], count: int) -> dict[str, Any]:
        """What the validation pictures show for the first ``count`` clips of a batch.

        Returns:
            ``clips`` (3·count, L, C, H, W): per clip the ground truth, the posterior-mean
            reconstruction (argmax offsets) and a prior sample, conditioning frames first;
            ``n_cond``; ``truth`` / ``predicted``: keyframes to mark on each of those rows
            (discovered ones on the first two, the sample's own on the third); ``offsets`` (B, M)
            argmax offsets of the whole batch and ``max_offset`` S, for the histogram.
        """
        was_training = self.training
        self.eval()
        clips, lengths = batch["frames"].to(self.device), batch["future_length"].to(self.device)
        posterior = self.model(clips, lengths, mode="posterior", sample=False)
        prior = self.model(clips[:count], lengths[:count], mode="prior", sample=True)
        self.train(was_training)
        self.freeze_stage1()
        discovered = self.discover(clips[:count], lengths[:count])
        truth = keyframe_lists(batch["keyframes"][:count])
        sampled = argmax_positions(prior["offset_probs"]).tolist()
        videos = [
            clips[:count], self.model.argmax_video(clips, posterior)[:count], self.model.argmax_video(clips[:count], prior)
        ]
        return {
            "clips": torch.stack(videos, dim=1).flatten(0, 1).cpu(),
            "n_cond": self.hparams.stage1["n_cond"],
            "truth": [marks for k in range(len(truth)) for marks in (truth[k], truth[k], [])],
            "predicted": [marks for k in range(len(truth)) for marks in (discovered[k], discovered[k], sampled[k])],
            "offsets": (posterior["offset_probs"].argmax(-1) + 1).cpu(),
            "max_offset": self.hparams.stage1["max_offset"],
        }

    def discoverers(self, name: str) -> dict[str, Callable]:
        """The discovery rules to score, by method name: the configured one first; with offset
        evidence also the other, as ``<name>_<rule>``."""
        rules = [self.hparams.discovery]
        if self.hparams.offset_evidence:
            rules += [rule for rule in KEYIN_RULES if rule != self.hparams.discovery]
        return {
            name if index == 0 else f"{name}_{rule}": functools.partial(self.discover, discovery=rule)
            for index, rule in enumerate(rules)
        }

    def configure_optimizers(self) -> torch.optim.Optimizer:
        trainable = [p for p in self.parameters() if p.requires_grad]
        return torch.optim.Adam(trainable, lr=self.hparams.lr, betas=(0.9, 0.999))
