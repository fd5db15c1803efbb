"""Stage 2: the keyframe predictor trained through the frozen interpolator (paper §3.1-3.2).

The encoder, decoder and interpolator of stage 1 are frozen (``requires_grad=False`` and
``.eval()``, re-asserted at every epoch and batch start) but gradients flow *through* them into
the keyframe predictor: LSTM_cond, LSTM_inf with the attention posterior, and LSTM_key with its
keyframe-embedding and offset heads. The loss is the soft keyframe loss (eq. 3-5).
"""

from __future__ import annotations

from dataclasses import asdict
from pathlib import Path
from typing import Any, Mapping

import lightning as L
import torch

from keyin.decode.prices import KNEE, MAP_CANDIDATE_LOGIT
from keyin.decode.registry import PAPER_RULE, model_rule
from keyin.decode.teacher import TeacherConfig, teacher_loss
from keyin.decode.trained import KeyframeReader, prices_of
from keyin.eval.f1 import discovery_summary, keyframe_lists
from keyin.decode.flat_hparams import typed_keyframe_arguments, upgrade_keyframe_hparams
from keyin.legacy import upgrade_state_dict
from keyin.models.modes import evaluating
from keyin.losses.image import frame_pixel_weights, future_pixel_weights
from keyin.losses.soft_keyframe import SoftLossConfig, keyin_loss, offset_entropy
from keyin.models.distributions import gaussian_kl
from keyin.models.config import KEYINConfig
from keyin.models.keyin import FROZEN_IN_STAGE2, KEYIN
from keyin.models.positions import argmax_positions
from keyin.lit.optimizers import OptimizerPartial, optimizer_partial, optimizer_spec, trained_parameters


class KeyframeModule(L.LightningModule):
    """Stage 2 of KEYIN (and of the Jumpy / Static baselines through ``offset_mode``): it trains and
    validates; its model finds keyframes through :meth:`reader` (:class:`keyin.decode.trained.KeyframeReader`)."""

    stage = "keyframes"
    monitor = ("val/f1", "max")  # best.ckpt: keyframe F1 on the validation clips

    def __init__(
        self,
        net: KEYINConfig | Mapping[str, Any],
        loss: SoftLossConfig | Mapping[str, Any],
        optimizer: OptimizerPartial | Mapping[str, Any],
        teacher: TeacherConfig | Mapping[str, Any] | None = None,  # ours, off by default (docs/decisions.md)
        discovery: str = PAPER_RULE,  # a rule of keyin.decode.registry.RULES
        map_keyframe_cost: float | str = 120.0,  # nats per keyframe, or "knee" (label-free)
        map_boundary_weight: float = 10.0,
        map_candidate_logit: float = MAP_CANDIDATE_LOGIT,  # discovery=map_pruned: a keyframe's least boundary logit
        frozen: str = "stage1",  # which stage-1 networks stage 2 freezes (models/keyin.py FROZEN_IN_STAGE2)
    ) -> None:
        """
        Args:
            net: the model's sizes and choices (a dict: :func:`dataclasses.asdict`'s).
            loss: the soft keyframe loss's weights.
            optimizer: a partial of a ``torch.optim`` class taking the parameters (or its spec,
                :func:`keyin.lit.optimizers.optimizer_spec`).
            teacher: the segmentation teacher; None: off.
            discovery, map_*: the discovery rule and its prices (:class:`keyin.decode.trained.KeyframeReader`).
            frozen: which of stage 1's networks stay frozen (:data:`keyin.models.keyin.FROZEN_IN_STAGE2`).
        """
        super().__init__()
        self.config = net if isinstance(net, KEYINConfig) else KEYINConfig.from_dict(net)
        self.loss = loss if isinstance(loss, SoftLossConfig) else SoftLossConfig(**loss)
        self.teacher = teacher if isinstance(teacher, TeacherConfig) else TeacherConfig(**(teacher or {}))
        model_rule(discovery, self.config.predictor.offset_evidence)
        if isinstance(map_keyframe_cost, str) and map_keyframe_cost != KNEE:
            raise ValueError(f"map_keyframe_cost must be nats per keyframe or {KNEE!r}, got {map_keyframe_cost!r}")
        if frozen not in FROZEN_IN_STAGE2:
            raise ValueError(f"frozen must be one of {tuple(FROZEN_IN_STAGE2)}, got {frozen!r}")
        # the checkpoint keeps plain dicts (weights_only loading), load_from_checkpoint rebuilds the configs
        self.save_hyperparameters(
            {"net": asdict(self.config), "loss": asdict(self.loss), "optimizer": optimizer_spec(optimizer),
             "teacher": asdict(self.teacher), "discovery": discovery, "map_keyframe_cost": map_keyframe_cost,
             "map_boundary_weight": map_boundary_weight, "map_candidate_logit": map_candidate_logit, "frozen": frozen},
            logger=False,  # the trackers get the whole run config (keyin.cli.tracking)
        )
        self.optimizer = optimizer_partial(self.hparams.optimizer)
        self.model = KEYIN.from_config(self.config)
        self.freeze_stage1()

    @classmethod
    def from_flat(cls, **flat: Any) -> "KeyframeModule":
        """The module of flat stage-2 hyper-parameters: ``model.keyframes`` of conf/model/keyin.yaml (the
        keys users override) with the stage-1 module's hyper-parameters as ``stage1``
        (:func:`keyin.decode.flat_hparams.typed_keyframe_arguments`)."""
        return cls(**typed_keyframe_arguments(flat))

    @classmethod
    def load_from_checkpoint(cls, checkpoint_path: str | Path, *args: Any, **kwargs: Any) -> "KeyframeModule":
        """Lightning's, with the flat hyper-parameters of a checkpoint saved before the typed configs
        upgraded (:func:`keyin.decode.flat_hparams.upgrade_keyframe_hparams`)."""
        saved = torch.load(checkpoint_path, map_location="cpu", weights_only=True)["hyper_parameters"]
        return super().load_from_checkpoint(checkpoint_path, *args, **{**upgrade_keyframe_hparams(saved), **kwargs})

    def reader(self) -> KeyframeReader:
        """This module's model read by its discovery rule at its prices (the model shared, not copied)."""
        return KeyframeReader(self.model, self.config, self.hparams.discovery, prices_of(self.hparams))

    def load_stage1(self, state_dict: dict[str, torch.Tensor]) -> None:
        """Copy the frozen modules' weights from a stage-1 checkpoint's state dict."""
        self.model.load_stage1(state_dict)

    @property
    def frozen_by_design(self) -> str:
        """What stays frozen in eval mode while stage 2 trains (said once by keyin.lit.run)."""
        return f"stage 2: stage 1's {', '.join(FROZEN_IN_STAGE2[self.hparams.frozen])}"

    def freeze_stage1(self) -> None:
        self.model.freeze_stage1(self.hparams.frozen)

    def train(self, mode: bool = True) -> "KeyframeModule":
        """Switch the trainable parts; stage 1 stays frozen in eval mode (docs/architecture.md, "Frozen modules")."""
        super().train(mode)
        self.freeze_stage1()
        return self

    def on_load_checkpoint(self, checkpoint: dict[str, Any]) -> None:
        # A keyin 0.1 checkpoint keeps the networks at the top level (encoder.*, predictor.*, ...).
        checkpoint["state_dict"] = upgrade_state_dict(checkpoint["state_dict"], self.stage)

    def on_train_batch_start(self, batch: Any, batch_idx: int) -> None:
        self.freeze_stage1()  # whatever switched modes since (docs/architecture.md, "Frozen modules")

    def soft_loss(self, clips: torch.Tensor, future_length: torch.Tensor, out: dict[str, torch.Tensor | None]) -> dict[str, torch.Tensor]:
        """The paper's loss (:func:`keyin.losses.soft_keyframe.keyin_loss`) of a posterior forward ``out``
        of (B, L, C, H, W) ``clips``, with this module's weights and reduction; with ``beta_ki > 0`` eq. 3's
        image term scores the decoded keyframes ``sigmoid(CNN_dec(K̂^{e,t}))`` against the soft targets K̃^t."""
        weights, n_cond = self.loss, self.model.n_cond
        key_frames = None
        if weights.beta_ki > 0:
            # float32, as the interpolated frames: these probabilities meet the loss's logs
            key_frames = torch.sigmoid(self.model.decoder(out["key_emb"]).float()).flatten(2)  # (B, M, C·H·W)
        return keyin_loss(
            out["offset_probs"], out["key_emb"], out["future_emb"], out["frames"], clips[:, n_cond:].flatten(2),
            gaussian_kl(out["mu"], out["log_sigma"]), future_length, weights.beta_ke, weights.beta_ki, weights.beta_kl,
            weights.normalize_key_targets, key_frames_pred=key_frames,
            pixel_weights=future_pixel_weights(frame_pixel_weights(clips, self.config.frames), n_cond),
            reduction=weights.reduction, latent_dim=self.config.predictor.latent_dim,
        )

    def _shared_step(self, batch: dict[str, torch.Tensor], stage: str) -> dict[str, torch.Tensor]:
        clips, future_length = batch["frames"], batch["future_length"]
        teacher = self.teacher
        out = self.model(clips, future_length)
        terms = self.soft_loss(clips, future_length, out)
        if stage == "train" and self.loss.entropy_bonus > 0:  # an aid the paper does not have (docs/decisions.md)
            weight = self.loss.entropy_weight(self.global_step)
            terms["loss"] = terms["loss"] - weight * offset_entropy(out["offset_probs"]).mean()
        if stage == "train" and teacher.weight > 0:  # ours, off in the paper's setting (docs/decisions.md)
            terms["teacher"] = teacher_loss(
                self.model, clips, out, future_length, teacher.keyframe_cost, teacher.clips, teacher.chain, teacher.leaves,
            )
            terms["loss"] = terms["loss"] + teacher.weight * terms["teacher"]
            self.log("train/teacher", terms["teacher"])
        logged = {"loss": terms["loss"], "offset_entropy": offset_entropy(out["offset_probs"]).mean()}
        logged |= {key: terms[key].mean() for key in ("inter", "key_emb", "kl")}
        logged |= {"n_inside": terms["c"].sum(-1).mean(), "coverage_end": terms["coverage"][:, -1].mean()}
        # under DDP, validation logs the mean over every rank's clips
        self.log_dict({f"{stage}/{key}": value for key, value in logged.items()}, prog_bar=stage == "train", sync_dist=stage == "val")
        return terms

    def training_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> torch.Tensor:
        return self._shared_step(batch, "train")["loss"]

    def validation_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> None:
        self._shared_step(batch, "val")
        for name, find in self.reader().discoverers("").items():
            summary = discovery_summary(find(batch["frames"], batch["future_length"]), batch["keyframes"])
            self.log_dict({f"val/{key}{name}": value for key, value in summary.items()}, prog_bar=not name, sync_dist=True)

    @torch.no_grad()
    def validation_pictures(self, batch: dict[str, torch.Tensor], count: int) -> dict[str, Any]:
        """What the validation pictures show for the first ``count`` clips of a batch.

        Returns:
            ``clips`` (3·count, L, C, H, W): per clip the ground truth, the posterior-mean
            reconstruction (argmax offsets) and a prior sample, conditioning frames first;
            ``n_cond``; ``truth`` / ``predicted``: keyframes to mark on each of those rows
            (discovered ones on the first two, the sample's own on the third); ``argmax_offsets`` (B, M)
            argmax offsets of the whole batch and ``max_offset`` S, for the histogram.
        """
        clips, lengths = batch["frames"].to(self.device), batch["future_length"].to(self.device)
        with evaluating(self):
            posterior = self.model(clips, lengths, mode="posterior", sample=False)
            prior = self.model(clips[:count], lengths[:count], mode="prior", sample=True)
            discovered = self.reader().discover(clips[:count], lengths[:count])
        truth = keyframe_lists(batch["keyframes"][:count])
        sampled = argmax_positions(prior["offset_probs"]).tolist()
        videos = [clips[:count], self.model.argmax_video(clips, posterior)[:count], self.model.argmax_video(clips[:count], prior)]
        return {
            "clips": torch.stack(videos, dim=1).flatten(0, 1).cpu(),
            "n_cond": self.model.n_cond,
            "truth": [marks for k in range(len(truth)) for marks in (truth[k], truth[k], [])],
            "predicted": [marks for k in range(len(truth)) for marks in (discovered[k], discovered[k], sampled[k])],
            "argmax_offsets": (posterior["offset_probs"].argmax(-1) + 1).cpu(),
            "max_offset": self.config.max_offset,
        }

    def configure_optimizers(self) -> torch.optim.Optimizer:
        return self.optimizer(trained_parameters(self))
