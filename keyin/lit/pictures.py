"""Pictures of a fixed validation batch at every validation, saved in the run dir and logged.

For modules with ``validation_pictures`` (KEYIN's stage 2 and Surprise): clips with their keyframes
marked (``pictures/val_step<N>.png`` and ``.gif``; stage 2: ground truth, reconstruction and a prior
sample; Surprise: ground truth and its one-step predictions), and a chart of the keyframe evidence:
stage 2's histogram of chosen offsets (``pictures/offsets_step<N>.png``), Surprise's KL curves
(``pictures/surprise_step<N>.png``). TensorBoard and wandb loggers also receive the PNGs (the GIFs stay in the folder).
"""

from __future__ import annotations

from pathlib import Path

import imageio.v3 as iio
import lightning as L
from lightning.pytorch.loggers import TensorBoardLogger, WandbLogger

from keyin.viz.keyframes import save_keyframe_pictures
from keyin.viz.report import save_offset_histogram, save_surprise_curves


def log_picture(loggers: list, key: str, path: Path, step: int) -> None:
    """Send a PNG to the loggers that take images (the CSV logger keeps only the file)."""
    for logger in loggers:
        if isinstance(logger, WandbLogger):
            logger.log_image(key=key, images=[str(path)], step=step)
        elif isinstance(logger, TensorBoardLogger):
            logger.experiment.add_image(key, iio.imread(path)[..., :3], step, dataformats="HWC")


class ValidationPictures(L.Callback):
    """Draws the first ``count`` validation clips after every validation (see module doc)."""

    def __init__(self, folder: Path, count: int = 4) -> None:
        self.folder, self.count = Path(folder), count

    def on_validation_epoch_end(self, trainer: L.Trainer, module: L.LightningModule) -> None:
        if trainer.sanity_checking or not trainer.is_global_zero or not hasattr(module, "validation_pictures"):
            return
        batch = next(iter(trainer.val_dataloaders))
        shown = module.validation_pictures(batch, self.count)
        step = trainer.global_step
        videos, _ = save_keyframe_pictures(
            self.folder, shown["clips"], shown["n_cond"], shown["truth"], shown["predicted"], name=f"val_step{step:06d}"
        )
        log_picture(trainer.loggers, "val/videos", videos, step)
        if "argmax_offsets" in shown:
            histogram = save_offset_histogram(
                shown["argmax_offsets"], shown["max_offset"], self.folder / f"offsets_step{step:06d}.png",
                title=f"argmax offsets on {len(shown['argmax_offsets'])} validation clips, step {step}",
            )
            log_picture(trainer.loggers, "val/offsets", histogram, step)
        if "surprise" in shown:
            curves = save_surprise_curves(
                shown["surprise"], shown["n_cond"], shown["surprise_truth"], shown["surprise_predicted"],
                self.folder / f"surprise_step{step:06d}.png", title=f"posterior KL per step, step {step}",
            )
            log_picture(trainer.loggers, "val/surprise", curves, step)
