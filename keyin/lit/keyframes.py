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
import torch.nn.functional as F

from keyin.eval.f1 import discovery_summary, keyframe_lists
from keyin.eval.segmentation import (
    boundary_keyframes,
    decode_by_length,
    embedding_costs,
    map_keyframes,
    segmentation_offsets,
    with_sequence_ends,
)
from keyin.losses.image import future_pixel_weights, model_pixel_weights
from keyin.losses.soft_keyframe import (
    argmax_frames,
    argmax_positions,
    gaussian_kl,
    keyin_loss,
    offset_teacher_loss,
    valid_frame_mask,
)
from keyin.lit.interpolator import InterpolatorModule
from keyin.models import KeyframePredictor

FROZEN = ("encoder", "decoder", "interpolator")
DISCOVERY_RULES = ("offsets", "boundaries", "map")


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
        if discovery not in DISCOVERY_RULES:
            raise ValueError(f"discovery must be one of {DISCOVERY_RULES}, got {discovery!r}")
        if discovery == "boundaries" and not offset_evidence:
            raise ValueError("discovery='boundaries' needs offset_evidence (the boundary scores)")
        self.save_hyperparameters()
        frozen = InterpolatorModule(**stage1)
        self.encoder, self.decoder, self.interpolator = frozen.encoder, frozen.decoder, frozen.interpolator
        self.predictor = KeyframePredictor(
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
        self.freeze_stage1()

    def pixel_weights(self, clips: torch.Tensor) -> torch.Tensor | None:
        """(B, L, C, H, W) weights of the image likelihood stage 1 was trained with, or None."""
        return model_pixel_weights(clips, self.hparams.stage1)

    def load_stage1(self, state_dict: dict[str, torch.Tensor]) -> None:
        """Copy the frozen modules' weights from a stage-1 checkpoint's state dict."""
        for name in FROZEN:
            prefix = f"{name}."
            part = {k[len(prefix) :]: v for k, v in state_dict.items() if k.startswith(prefix)}
            getattr(self, name).load_state_dict(part)

    def freeze_stage1(self) -> None:
        for name in FROZEN:
            module = getattr(self, name)
            module.requires_grad_(False)
            module.eval()

    def on_train_epoch_start(self) -> None:
        self.freeze_stage1()

    def on_train_batch_start(self, batch: Any, batch_idx: int) -> None:
        # Lightning puts every module back in train mode after validation (REFERENCE §8.1).
        self.freeze_stage1()

    def forward(
        self, clips: torch.Tensor, future_length: torch.Tensor, mode: str = "posterior", sample: bool = True
    ) -> dict[str, torch.Tensor]:
        """Keyframes, offsets and interpolated frames of a batch of clips.

        Args:
            clips: (B, L, C, H, W) in [0, 1], L = n_cond + n_future.
            future_length: (B,) valid future frames.
        Returns:
            ``key_emb`` (B, M, E), ``offset_probs`` (B, M, S), ``mu``/``log_sigma`` (B, M, Zk),
            ``attention`` (B, M, N), ``future_emb`` (B, N, E), ``frames`` (B, M, S, C·H·W)
            probabilities of the interpolated frames.
        """
        n_cond = self.hparams.stage1["n_cond"]
        embeddings = self.encoder(clips)  # (B, L, E)
        cond_emb, future_emb = embeddings[:, :n_cond], embeddings[:, n_cond:]
        keys = self.predictor(cond_emb, future_emb, future_length, mode=mode, sample=sample)
        starts = torch.cat([cond_emb[:, -1:], keys.key_emb[:, :-1]], dim=1)  # (B, M, E)
        n_clips, n_keys, max_offset = keys.offset_probs.shape
        latent = torch.randn(
            n_clips * n_keys, self.interpolator.latent_dim, device=clips.device
        )  # stage 2 samples the interpolator latent from the prior (paper §3.2)
        inter_emb = self.interpolator(
            starts.flatten(0, 1), keys.key_emb.flatten(0, 1), keys.offset_probs.flatten(0, 1), latent
        )  # (B·M, S, E)
        frames = torch.sigmoid(self.decoder(inter_emb.flatten(0, 1)))  # (B·M·S, C, H, W)
        return {
            "key_emb": keys.key_emb,
            "offset_probs": keys.offset_probs,
            "mu": keys.mu,
            "log_sigma": keys.log_sigma,
            "attention": keys.attention,
            "future_emb": future_emb,
            "boundary_emb": embeddings[:, n_cond - 1 :],
            "offset_logits": keys.offset_logits,
            "boundary_scores": keys.boundary_scores,
            "frames": frames.reshape(n_clips, n_keys, max_offset, -1),
        }

    def _shared_step(self, batch: dict[str, torch.Tensor], stage: str) -> dict[str, torch.Tensor]:
        clips, future_length = batch["frames"], batch["future_length"]
        n_cond = self.hparams.stage1["n_cond"]
        out = self(clips, future_length)
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
        entropy = -(out["offset_probs"] * out["offset_probs"].clamp_min(1e-12).log()).sum(-1)
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
        """Cross-entropy of δ to the exact best segmentation under the frozen interpolator.

        Optional (``teacher_weight`` > 0, off in the paper's setting): the DP of
        :mod:`keyin.eval.segmentation` on the decoder-free embedding costs gives, for each clip,
        the hard offsets that minimise the interpolation error between the true frames — the
        optimum the soft loss relaxes; with ``offset_evidence`` also a per-frame cross-entropy of
        the boundary scores to its boundaries. It keeps δ from collapsing to one offset for every
        clip (docs/decisions.md). Computed on the first ``teacher_clips`` clips (0: all); each clip
        is segmented within its own valid frames, and padding gets no boundary label.
        """
        n_clips = self.hparams.teacher_clips or out["boundary_emb"].shape[0]
        boundary_emb = out["boundary_emb"][:n_clips].detach()
        lengths = future_length[:n_clips].cpu()
        n_future = boundary_emb.shape[1] - 1
        positions = decode_by_length(
            lambda rows, length: embedding_costs(self.interpolator, boundary_emb[rows.to(boundary_emb.device), : length + 1]),
            lengths, self.hparams.n_keyframes, self.predictor.max_offset, self.hparams.teacher_keyframe_cost,
        )
        targets = segmentation_offsets(positions, n_future, self.hparams.n_keyframes)
        loss = offset_teacher_loss(out["offset_logits"][:n_clips], targets.to(boundary_emb.device))
        if out["boundary_scores"] is not None:
            # With offset evidence, the per-frame boundary scores learn the segmentation directly.
            labels = torch.zeros(n_clips, n_future)
            for row, clip_positions in enumerate(positions):
                labels[row, clip_positions] = 1.0
            scores = out["boundary_scores"][:n_clips]
            valid = valid_frame_mask(lengths, n_future).to(scores.device)  # padding gets no label
            loss = loss + F.binary_cross_entropy_with_logits(scores[valid], labels.to(scores)[valid])
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
        """Keyframe positions in posterior mode with the posterior mean, inside each clip.

        Args:
            discovery: "offsets" (the paper's: argmax offsets, positions by their sums, §3.9),
                "boundaries" (with ``offset_evidence``: the most likely keyframe set under
                LSTM_inf's per-frame boundary scores, within M gaps of at most S) or "map" (the
                exact best segmentation under the frozen interpolator's pixel BCE with
                ``map_keyframe_cost`` per keyframe, plus ``map_boundary_weight`` times the
                boundary scores where there are any); default: the module's ``discovery``.
        """
        discovery = discovery or self.hparams.discovery
        was_training = self.training
        self.eval()
        embeddings = self.encoder(clips.to(self.device))
        n_cond = self.hparams.stage1["n_cond"]
        keys = self.predictor(
            embeddings[:, :n_cond], embeddings[:, n_cond:], future_length.to(self.device),
            mode="posterior", sample=False,
        )
        self.train(was_training)
        self.freeze_stage1()
        if discovery == "boundaries":
            interior = boundary_keyframes(
                keys.boundary_scores, future_length.cpu(), self.hparams.n_keyframes, self.predictor.max_offset
            )
            return with_sequence_ends(interior, future_length.cpu(), clips.shape[1] - n_cond)
        if discovery == "map":
            clips = clips.to(self.device)
            interior = map_keyframes(
                self.interpolator, self.decoder, embeddings[:, n_cond - 1 :], clips[:, n_cond:].flatten(2),
                future_length, self.hparams.n_keyframes, self.hparams.map_keyframe_cost,
                keys.boundary_scores, self.hparams.map_boundary_weight,
                weights=future_pixel_weights(self.pixel_weights(clips), n_cond),
            )
            return with_sequence_ends(interior, future_length.cpu(), clips.shape[1] - n_cond)
        positions = argmax_positions(keys.offset_probs).cpu()
        return [
            [p for p in row.tolist() if p < length] for row, length in zip(positions, future_length.tolist())
        ]

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
        posterior = self(clips, lengths, mode="posterior", sample=False)
        prior = self(clips[:count], lengths[:count], mode="prior", sample=True)
        self.train(was_training)
        self.freeze_stage1()
        discovered = self.discover(clips[:count], lengths[:count])
        truth = keyframe_lists(batch["keyframes"][:count])
        sampled = argmax_positions(prior["offset_probs"]).tolist()
        videos = [clips[:count], self.argmax_video(clips, posterior)[:count], self.argmax_video(clips[:count], prior)]
        return {
            "clips": torch.stack(videos, dim=1).flatten(0, 1).cpu(),
            "n_cond": self.hparams.stage1["n_cond"],
            "truth": [marks for k in range(len(truth)) for marks in (truth[k], truth[k], [])],
            "predicted": [marks for k in range(len(truth)) for marks in (discovered[k], discovered[k], sampled[k])],
            "offsets": (posterior["offset_probs"].argmax(-1) + 1).cpu(),
            "max_offset": self.hparams.stage1["max_offset"],
        }

    def argmax_video(self, clips: torch.Tensor, out: dict[str, torch.Tensor]) -> torch.Tensor:
        """(B, L, C, H, W): the conditioning frames, then the frames of the argmax offsets."""
        n_cond = self.hparams.stage1["n_cond"]
        future = argmax_frames(out["offset_probs"], out["frames"], clips.shape[1] - n_cond)  # (B, N, D)
        return torch.cat([clips[:, :n_cond], future.view_as(clips[:, n_cond:])], dim=1)

    def discoverers(self, name: str) -> dict[str, Callable]:
        """The discovery rules to score, by method name: the configured one first; with offset
        evidence also the other, as ``<name>_<rule>``."""
        rules = [self.hparams.discovery]
        if self.hparams.offset_evidence:
            rules += [rule for rule in DISCOVERY_RULES if rule != self.hparams.discovery]
        return {
            name if index == 0 else f"{name}_{rule}": functools.partial(self.discover, discovery=rule)
            for index, rule in enumerate(rules)
        }

    def configure_optimizers(self) -> torch.optim.Optimizer:
        trainable = [p for p in self.parameters() if p.requires_grad]
        return torch.optim.Adam(trainable, lr=self.hparams.lr, betas=(0.9, 0.999))
