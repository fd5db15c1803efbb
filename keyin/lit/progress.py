"""A progress bar for step-based training: steps of the stage toward its max_steps."""

from __future__ import annotations

from typing import Any

import lightning as L
from lightning.pytorch.callbacks import TQDMProgressBar


class StepProgressBar(TQDMProgressBar):
    """Counts the stage's optimizer steps up to ``max_steps``, named by the stage (``keyframes:
    2/3``), where Lightning's bar counts epochs that step-based training does not have
    (``max_epochs=-1`` read ``Epoch 0/-2``)."""

    def on_train_epoch_start(self, trainer: L.Trainer, *_: Any) -> None:
        super().on_train_epoch_start(trainer)
        bar = self.train_progress_bar
        bar.reset(total=trainer.max_steps)
        bar.n = trainer.global_step  # a resumed stage starts where it stopped
        bar.set_description(trainer.lightning_module.stage)

    def on_train_batch_end(self, trainer: L.Trainer, module: L.LightningModule, outputs: Any, batch: Any, batch_idx: int) -> None:
        super().on_train_batch_end(trainer, module, outputs, batch, trainer.global_step - 1)  # its count: the global step
