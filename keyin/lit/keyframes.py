"""Stage 2: the keyframe predictor trained through the frozen interpolator (paper §3.1-3.2).

The encoder, decoder and interpolator of stage 1 are frozen (``requires_grad=False`` and
``.eval()``, re-asserted at every epoch and batch start) but gradients flow *through* them into
the keyframe predictor: LSTM_cond, LSTM_inf with the attention posterior, and LSTM_key with its
keyframe-embedding and offset heads. The loss is the soft keyframe loss (eq. 3-5).
"""

from __future__ import annotations

from typing import Any

import lightning as L
import torch

from keyin.decode.registry import KNEE, MAP_CANDIDATE_LOGIT, PAPER_RULE, model_rule
from keyin.decode.teacher import teacher_loss
from keyin.decode.trained import KeyframeRules, keyin_model
from keyin.eval.f1 import discovery_summary, keyframe_lists
from keyin.lit.legacy import upgrade_state_dict
from keyin.models.modes import evaluating
from keyin.losses.image import future_pixel_weights
from keyin.losses.soft_keyframe import REDUCTIONS, keyin_loss, offset_entropy
from keyin.models.distributions import gaussian_kl
from keyin.models.keyin import FROZEN_IN_STAGE2
from keyin.models.positions import argmax_positions
from keyin.lit.optimizers import adam


class KeyframeModule(KeyframeRules, L.LightningModule):
    """Stage 2 of KEYIN (and of the Jumpy / Static baselines through ``offset_mode``); its discovery
    rules are :class:`keyin.decode.trained.KeyframeRules`'."""

    stage = "keyframes"
    monitor = ("val/f1", "max")  # best.ckpt: keyframe F1 on the validation clips

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
        # our additions (docs/decisions.md); these defaults are the paper's method
        teacher_weight: float = 0.0,
        teacher_clips: int = 0,
        offset_evidence: bool = False,
        discovery: str = PAPER_RULE,  # a rule of keyin.decode.registry.RULES
        teacher_keyframe_cost: float | str = 0.0,  # nats per keyframe in the teacher's DP, or "knee"
        teacher_chain: bool = False,  # teacher forcing of the previous keyframe's position (decode/teacher.py)
        teacher_leaves: bool = False,  # the teacher also says where the chain leaves the clip
        map_keyframe_cost: float | str = 120.0,  # nats per keyframe, or "knee" (label-free)
        map_boundary_weight: float = 10.0,
        map_candidate_logit: float = MAP_CANDIDATE_LOGIT,  # discovery=map_pruned: a keyframe's least boundary logit
        # the paper's open choices (docs/decisions.md "The paper's stage 2: every open choice measured")
        delta_input: str = "soft",  # what the frozen interpolator reads of δ (models/keyin.py DELTA_INPUTS)
        loss_reduction: str = "sum",  # what the β's weigh against (losses/soft_keyframe.py REDUCTIONS)
        # a label-free optimisation aid the paper does not have: + w·H(δ) rewarded, w decaying linearly
        # from entropy_bonus to 0 over entropy_bonus_steps training steps
        entropy_bonus: float = 0.0,
        entropy_bonus_steps: int = 0,
        gumbel_offsets: bool = False,  # an aid the paper does not have (models/keyin.py)
        frozen: str = "stage1",  # which stage-1 networks stage 2 freezes (models/keyin.py FROZEN_IN_STAGE2)
        interpolate_from: str = "predicted",  # ours: "frames" (models/keyin.py INTERPOLATE_FROM)
    ) -> None:
        super().__init__()
        model_rule(discovery, offset_evidence)
        if isinstance(map_keyframe_cost, str) and map_keyframe_cost != KNEE:
            raise ValueError(f"map_keyframe_cost must be nats per keyframe or {KNEE!r}, got {map_keyframe_cost!r}")
        if frozen not in FROZEN_IN_STAGE2:
            raise ValueError(f"frozen must be one of {tuple(FROZEN_IN_STAGE2)}, got {frozen!r}")
        if loss_reduction not in REDUCTIONS:
            raise ValueError(f"loss_reduction must be one of {REDUCTIONS}, got {loss_reduction!r}")
        if entropy_bonus < 0 or (entropy_bonus > 0 and entropy_bonus_steps < 1):
            raise ValueError(
                f"entropy_bonus must be >= 0 and, when > 0, decay over entropy_bonus_steps >= 1 steps; "
                f"got {entropy_bonus} over {entropy_bonus_steps}"
            )
        self.save_hyperparameters(logger=False)  # the trackers get the whole run config (keyin.cli.tracking)
        self.model = keyin_model(self.hparams)
        self.freeze_stage1()

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
        hp, n_cond = self.hparams, self.model.n_cond
        key_frames = None
        if hp.beta_ki > 0:
            # float32, as the interpolated frames: these probabilities meet the loss's logs
            key_frames = torch.sigmoid(self.model.decoder(out["key_emb"]).float()).flatten(2)  # (B, M, C·H·W)
        return keyin_loss(
            out["offset_probs"], out["key_emb"], out["future_emb"], out["frames"], clips[:, n_cond:].flatten(2),
            gaussian_kl(out["mu"], out["log_sigma"]), future_length, hp.beta_ke, hp.beta_ki, hp.beta_kl,
            hp.normalize_key_targets, key_frames_pred=key_frames,
            pixel_weights=future_pixel_weights(self.pixel_weights(clips), n_cond),
            reduction=hp.loss_reduction, latent_dim=hp.latent_dim,
        )

    def _shared_step(self, batch: dict[str, torch.Tensor], stage: str) -> dict[str, torch.Tensor]:
        clips, future_length = batch["frames"], batch["future_length"]
        hp = self.hparams
        out = self.model(clips, future_length)
        terms = self.soft_loss(clips, future_length, out)
        if stage == "train" and hp.entropy_bonus > 0:  # an aid the paper does not have (docs/decisions.md)
            weight = hp.entropy_bonus * max(0.0, 1.0 - self.global_step / hp.entropy_bonus_steps)
            terms["loss"] = terms["loss"] - weight * offset_entropy(out["offset_probs"]).mean()
        if stage == "train" and hp.teacher_weight > 0:  # ours, off in the paper's setting (docs/decisions.md)
            terms["teacher"] = teacher_loss(
                self.model, clips, out, future_length, hp.teacher_keyframe_cost, hp.teacher_clips, hp.teacher_chain,
                hp.teacher_leaves,
            )
            terms["loss"] = terms["loss"] + hp.teacher_weight * terms["teacher"]
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
        for name, find in self.discoverers("").items():
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
        discovered, truth = self.discover(clips[:count], lengths[:count]), keyframe_lists(batch["keyframes"][:count])
        sampled = argmax_positions(prior["offset_probs"]).tolist()
        videos = [clips[:count], self.model.argmax_video(clips, posterior)[:count], self.model.argmax_video(clips[:count], prior)]
        return {
            "clips": torch.stack(videos, dim=1).flatten(0, 1).cpu(),
            "n_cond": self.model.n_cond,
            "truth": [marks for k in range(len(truth)) for marks in (truth[k], truth[k], [])],
            "predicted": [marks for k in range(len(truth)) for marks in (discovered[k], discovered[k], sampled[k])],
            "argmax_offsets": (posterior["offset_probs"].argmax(-1) + 1).cpu(),
            "max_offset": self.hparams.stage1["max_offset"],
        }

    def configure_optimizers(self) -> torch.optim.Optimizer:
        return adam(self, self.hparams.lr)
