"""The TAP baseline of Table 2: a subgoal between a start and a goal frame, trained with the
minimum-over-time loss (paper §4.2; Jayaraman et al. 2019).

One stage. Each training step draws per clip a start a and a goal b inside its valid frames
(:func:`keyin.losses.tap.sample_pairs`: b - a uniform in [min_gap, max_gap], then a uniform),
predicts one frame from (I_a, I_b) and scores it against the best-matching frame
a + margin < t < b - margin. Validation and test use each clip's first and last valid frame.
TAP finds no keyframes; the planner asks it for :meth:`TAPModule.subgoal`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import lightning as L
import torch
from torch.utils.data import Dataset

from keyin.eval.tap import save_subgoal_grid, score_whole_clips
from keyin.models.modes import evaluating
from keyin.losses.image import model_pixel_weights
from keyin.losses.tap import (
    argmin_times, pair_autoencoding_bce, pair_bce, pair_images, sample_pairs, shortest_gap, whole_clip_pairs,
)
from keyin.models import TAPNetwork
from keyin.lit.optimizers import adam


class TAPModule(L.LightningModule):
    """TAP's bottleneck predictor with KEYIN's encoder/decoder sizes.

    Args:
        n_cond: conditioning frames at the start of each clip (they count as frames here: the
            first one is the start of the evaluation pair).
        mlp_layers: Linear layers of the bottleneck MLP.
        margin: frames excluded next to each end of the pair besides a and b themselves.
        min_gap: the least b - a drawn in training; None: the least that leaves one admissible
            frame (2·margin + 2).
        max_gap: the most b - a drawn in training; None: the whole valid clip.
        foreground_weight, foreground_threshold: the image likelihood's weight of changed pixels,
            as in KEYIN's stage 1 (keyin/losses/image.py; 1: plain BCE).
        ae_weight: weight of an auto-encoding BCE of the start and goal frames through the encoder
            and decoder (the bottleneck skipped), as in KEYIN's stage 1 and Surprise. Without it
            the pushing model predicts one blurred mean image for every pair (docs/baselines.md).
        The other arguments size :class:`keyin.models.TAPNetwork`; ``lr`` is Adam's.
    """

    stage = "tap"
    monitor = ("val/loss", "min")  # best.ckpt: its loss on the validation clips

    def __init__(
        self,
        image_size: int,
        channels: int,
        n_cond: int,
        embed_dim: int,
        conv_width: int,
        coord_channels: bool,
        norm: str,
        mlp_hidden: int,
        lr: float,
        mlp_layers: int = 3,
        margin: int = 1,
        min_gap: int | None = None,
        max_gap: int | None = None,
        foreground_weight: float = 1.0,
        foreground_threshold: float = 0.1,
        ae_weight: float = 0.0,
    ) -> None:
        super().__init__()
        self.save_hyperparameters(logger=False)  # the trackers get the whole run config (keyin.cli.tracking)
        if margin < 0:
            raise ValueError(f"TAP's margin={margin} must be >= 0")
        self.least_gap = shortest_gap(margin) if min_gap is None else min_gap
        if self.least_gap < shortest_gap(margin) or (max_gap is not None and max_gap < self.least_gap):
            raise ValueError(
                f"TAP needs 2 * margin + 2 <= min_gap <= max_gap, got margin={margin}, min_gap={min_gap}, "
                f"max_gap={max_gap}"
            )
        self.network = TAPNetwork(
            image_size, channels, embed_dim, conv_width, coord_channels, norm, mlp_hidden, mlp_layers
        )

    def pair_terms(
        self, frames: torch.Tensor, n_valid: torch.Tensor, start: torch.Tensor, goal: torch.Tensor
    ) -> tuple[torch.Tensor, torch.Tensor]:
        """Min-over-time loss (B,) and chosen frame (B,) of predictions between ``start`` and
        ``goal`` (B,) of (B, L, C, H, W) clips with ``n_valid`` (B,) valid frames
        (:func:`keyin.losses.tap.pair_bce`)."""
        frames, n_valid, start, goal = (x.to(self.device) for x in (frames, n_valid, start, goal))
        weights = model_pixel_weights(frames, self.hparams)
        logits = self.network(*pair_images(frames, start, goal))
        return pair_bce(logits, frames, n_valid, start, goal, self.hparams.margin, weights)

    def _shared_step(self, batch: dict[str, torch.Tensor], stage: str) -> torch.Tensor:
        frames = batch["frames"]
        n_valid = self.hparams.n_cond + batch["future_length"]
        if stage == "train":
            start, goal = sample_pairs(n_valid, self.least_gap, self.hparams.max_gap)
        else:
            start, goal = whole_clip_pairs(n_valid)
        weights = model_pixel_weights(frames, self.hparams)
        images, reconstruction = pair_images(frames, start, goal), None
        if self.hparams.ae_weight > 0:  # the prediction and the auto-encoded pair in one decoder batch (BatchNorm)
            logits, reconstruction = self.network.predict_and_reconstruct(*images)
        else:
            logits = self.network(*images)
        loss, argmin = pair_bce(logits, frames, n_valid, start, goal, self.hparams.margin, weights)
        relative, at_last = argmin_times(argmin, start, goal, self.hparams.margin)
        mean_loss = loss.mean()
        terms = {
            f"{stage}/bce_per_pixel": mean_loss / frames[0, 0].numel(),  # of the min-over-time loss
            f"{stage}/argmin_relative": relative.mean(),  # (t - a) / (b - a) of the chosen frame
            f"{stage}/argmin_last": at_last.float().mean(),  # chosen frame = the last admissible one
        }
        if reconstruction is not None:
            autoencoding = pair_autoencoding_bce(reconstruction, frames, start, goal, weights)
            terms[f"{stage}/autoencoding_per_pixel"] = autoencoding.mean() / (2 * frames[0, 0].numel())
            mean_loss = mean_loss + self.hparams.ae_weight * autoencoding.mean()
        self.log_dict(
            {f"{stage}/loss": mean_loss, **terms},
            prog_bar=stage == "train",
            sync_dist=stage == "val",  # under DDP: the mean over every rank's clips
        )
        return mean_loss

    def training_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> torch.Tensor:
        return self._shared_step(batch, "train")

    def validation_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> None:
        self._shared_step(batch, "val")

    @torch.no_grad()
    def subgoal(self, start_images: torch.Tensor, goal_images: torch.Tensor) -> torch.Tensor:
        """TAP's prediction between (B, C, H, W) start and goal images in [0, 1]: (B, C, H, W)
        in [0, 1], on the inputs' device."""
        with evaluating(self):
            logits = self.network(start_images.to(self.device), goal_images.to(self.device))
        return torch.sigmoid(logits).to(start_images.device)

    @torch.no_grad()
    def test_metrics(self, clips: Dataset, folder: Path) -> dict[str, float | int]:
        """Scores on ``clips`` (:func:`keyin.eval.tap.score_whole_clips`) and ``tap_grid.png`` in
        ``folder``; keyin-train writes them to metrics.json."""
        self.eval()
        save_subgoal_grid(self.subgoal, clips, self.hparams.n_cond, folder)
        return score_whole_clips(self.pair_terms, clips, self.hparams.n_cond, self.hparams.margin)

    def discoverers(self, name: str) -> dict[str, Callable]:
        """None: TAP predicts subgoal images, not keyframe positions."""
        return {}

    def configure_optimizers(self) -> torch.optim.Optimizer:
        return adam(self, self.hparams.lr)
