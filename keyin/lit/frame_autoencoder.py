"""The frame autoencoder (issue 25): one stage on single frames, the frame model that stage 1 and
stage 2 can share frozen, with the dataset's embeddings cached once (keyin.data.embeddings).

Each training step draws ``frames_per_clip`` valid frames of every clip of the batch and scores
their reconstruction with the image likelihood of KEYIN's stage 1 (changed pixels weighted,
keyin/losses/image.py, against the clip's first frame). Validation and test score every valid frame:
the BCE per frame and, on RGB frames, where the reconstructions put the puck and the pusher
(:mod:`keyin.eval.placement`; nothing where a dataset has no such objects).
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import lightning as L
import torch
import torch.nn.functional as F
from torch.utils.data import DataLoader, Dataset

from keyin.data.segments import valid_frames
from keyin.eval.placement import FramePlacement, frame_placements
from keyin.models.modes import evaluating
from keyin.losses.image import model_pixel_weights
from keyin.models import FrameAutoencoder
from keyin.viz.keyframes import save_keyframe_pictures
from keyin.lit.optimizers import adam


def placement_metrics(placements: dict[str, FramePlacement], prefix: str) -> dict[str, float]:
    """``<prefix><object>_drawn`` / ``_error_px`` / ``_iou`` of the objects that appear at all."""
    metrics = {}
    for name, frames in placements.items():
        summary = frames.summary()
        if summary.frames:
            metrics.update({f"{prefix}{name}_drawn": summary.drawn, f"{prefix}{name}_iou": summary.iou,
                            f"{prefix}{name}_within_2px": summary.within_2px})
            if summary.drawn > 0:
                metrics[f"{prefix}{name}_error_px"] = summary.centroid_error_px
    return metrics


class FrameAutoencoderModule(L.LightningModule):
    """Trains a :class:`keyin.models.FrameAutoencoder` on single frames of the clips.

    Args:
        n_cond: conditioning frames at the start of each clip (frames like any other here).
        frames_per_clip: valid frames drawn per clip and training step (uniformly, with replacement).
        foreground_weight, foreground_threshold: the image likelihood's weight of changed pixels
            (keyin/losses/image.py; 1: plain BCE).
        The other arguments size the autoencoder; ``lr`` is Adam's.
    """

    stage = "frames"
    monitor = ("val/bce_per_frame", "min")  # best.ckpt: reconstruction error on the validation clips

    def __init__(
        self,
        image_size: int,
        channels: int,
        n_cond: int,
        embed_dim: int,
        conv_width: int,
        coord_channels: bool,
        norm: str,
        lr: float,
        frames_per_clip: int = 4,
        foreground_weight: float = 1.0,
        foreground_threshold: float = 0.1,
    ) -> None:
        super().__init__()
        if frames_per_clip < 1:
            raise ValueError(f"frames_per_clip={frames_per_clip} must be >= 1")
        self.save_hyperparameters(logger=False)  # the trackers get the whole run config (keyin.cli.tracking)
        self.network = FrameAutoencoder(image_size, channels, conv_width, embed_dim, coord_channels, norm)

    def reconstruction(self, clips: torch.Tensor, clip: torch.Tensor, frame: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """Summed (pixel-weighted) BCE of reconstructing frames ``(clip, frame)`` (each (F,)) of
        (B, L, C, H, W) clips, the weights comparing each frame with its clip's first, and the
        reconstructions' (F, C, H, W) logits."""
        frames = clips[clip, frame]  # (F, C, H, W)
        pairs = torch.stack([clips[clip, 0], frames], dim=1)  # (F, 2, C, H, W): reference, frame
        weights = model_pixel_weights(pairs, self.hparams)  # only the drawn frames' weights
        logits = self.network(frames)[1]
        weights = None if weights is None else weights[:, 1]
        bce = F.binary_cross_entropy_with_logits(logits, frames, weights, reduction="sum")
        return bce, logits

    def valid_reconstruction(self, batch: dict[str, torch.Tensor]) -> tuple[torch.Tensor, torch.Tensor, torch.Tensor]:
        """Summed BCE, logits and true frames (F, C, H, W) of every valid frame of a batch."""
        clips = batch["frames"].to(self.device)
        lengths = self.hparams.n_cond + batch["future_length"].to(self.device)  # (B,)
        clip, frame = valid_frames(lengths, clips.shape[1]).nonzero(as_tuple=True)
        return *self.reconstruction(clips, clip, frame), clips[clip, frame]

    def training_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> torch.Tensor:
        clips = batch["frames"]
        n_valid = self.hparams.n_cond + batch["future_length"]  # (B,)
        draws = torch.rand(len(clips), self.hparams.frames_per_clip, device=clips.device)
        frame = (draws * n_valid[:, None]).long().flatten()  # (B·k,)
        clip = torch.arange(len(clips), device=clips.device).repeat_interleave(self.hparams.frames_per_clip)
        loss = self.reconstruction(clips, clip, frame)[0] / len(frame)
        self.log("train/bce_per_frame", loss, prog_bar=True)
        return loss

    def validation_step(self, batch: dict[str, torch.Tensor], batch_idx: int) -> None:
        bce, logits, frames = self.valid_reconstruction(batch)
        self.log("val/bce_per_frame", bce / len(frames), sync_dist=True)
        if self.hparams.channels == 3:  # which keys exist depends on the clips: not reduced over DDP's ranks
            # (a rank would wait for a key another never logs); the logger shows rank 0's clips
            self.log_dict(placement_metrics(frame_placements(torch.sigmoid(logits), frames), "val/"))

    @torch.no_grad()
    def reconstruct(self, frames: torch.Tensor) -> torch.Tensor:
        """(..., C, H, W) frames in [0, 1] -> their reconstructions, in [0, 1]."""
        with evaluating(self):
            return torch.sigmoid(self.network(frames.to(self.device))[1])

    @torch.no_grad()
    def test_metrics(self, clips: Dataset, folder: Path, batch_size: int = 50) -> dict[str, float | int]:
        """BCE per frame and object placement over every valid frame of ``clips``, and
        ``reconstructions.png`` (truth above reconstruction, four clips) in ``folder``; keyin-train
        writes them to metrics.json."""
        self.eval()
        bce, frames_seen, parts = 0.0, 0, {}
        for batch in DataLoader(clips, batch_size=batch_size, shuffle=False):
            batch_bce, logits, frames = self.valid_reconstruction(batch)
            bce += float(batch_bce)
            frames_seen += len(frames)
            if self.hparams.channels == 3:
                for name, placement in frame_placements(torch.sigmoid(logits), frames).items():
                    parts.setdefault(name, []).append(placement)
        first = next(iter(DataLoader(clips, batch_size=min(4, len(clips)), shuffle=False)))["frames"]
        pairs = torch.stack([first, self.reconstruct(first).cpu()], dim=1).flatten(0, 1)  # (2K, L, C, H, W)
        nothing = [[] for _ in pairs]
        save_keyframe_pictures(folder, pairs, self.hparams.n_cond, nothing, nothing, name="reconstructions", per_column=2)
        placements = {name: FramePlacement.cat(part) for name, part in parts.items()}
        return {"bce_per_frame": bce / frames_seen, "frames": frames_seen, "n_sequences": len(clips),
                **placement_metrics(placements, "")}

    def discoverers(self, name: str) -> dict[str, Callable]:
        """None: a frame model finds no keyframes."""
        return {}

    def configure_optimizers(self) -> torch.optim.Optimizer:
        return adam(self, self.hparams.lr)
