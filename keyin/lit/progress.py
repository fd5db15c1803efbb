"""Progress of step-based training, the stage's steps toward its max_steps: a bar on a terminal, a line now and then in a
log file (a batch job's, ``nohup``'s), where a bar's carriage returns would make one ever-growing line."""

from __future__ import annotations

import sys
import time
from typing import Any, TextIO

import lightning as L
from lightning.pytorch.callbacks import Callback, ProgressBar, TQDMProgressBar


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


class StepLogLines(ProgressBar):
    """One line per ``every_seconds`` of training (and at the stage's last step) on ``stream``: the stage, its step
    of max_steps, seconds per step since the last line, the time left at that pace and the bar's metrics
    (``keyframes: step 500/5000 · 1.82 s/step · 2h16m left · train/loss=1.9e+03``). Lightning's progress bar
    (one per trainer) in a log file: Lightning adds no bar of its own beside it and silences it on ranks above 0."""

    def __init__(self, every_seconds: float = 60.0, stream: TextIO | None = None) -> None:
        super().__init__()
        self.every_seconds = every_seconds
        self.stream = stream
        self._enabled = True
        self._since: tuple[float, int] = (0.0, 0)

    def disable(self) -> None:
        self._enabled = False

    def enable(self) -> None:
        self._enabled = True

    def on_train_start(self, trainer: L.Trainer, module: L.LightningModule) -> None:
        self._since = (time.monotonic(), trainer.global_step)

    def on_train_batch_end(self, trainer: L.Trainer, module: L.LightningModule, *_: Any) -> None:
        now, step = time.monotonic(), trainer.global_step
        if not self._enabled or (now - self._since[0] < self.every_seconds and step < trainer.max_steps):
            return
        pace = (now - self._since[0]) / max(step - self._since[1], 1)
        metrics = " ".join(f"{name}={value:.3g}" for name, value in trainer.progress_bar_metrics.items())  # as the bar shows
        print(f"{module.stage}: step {step}/{trainer.max_steps} · {pace:.2f} s/step · "
              f"{duration(pace * (trainer.max_steps - step))} left · {metrics}".rstrip(" ·"),
              file=self.stream or sys.stdout, flush=True)
        self._since = (now, step)


def duration(seconds: float) -> str:
    """``2h16m``, ``4m05s`` or ``12s``."""
    minutes, secs = divmod(int(round(seconds)), 60)
    hours, minutes = divmod(minutes, 60)
    return f"{hours}h{minutes:02d}m" if hours else f"{minutes}m{secs:02d}s" if minutes else f"{secs}s"


def step_progress(stream: TextIO | None = None) -> Callback:
    """:class:`StepProgressBar` where ``stream`` (default: stdout) is a terminal, else :class:`StepLogLines`."""
    stream = stream or sys.stdout
    return StepProgressBar() if stream.isatty() else StepLogLines(stream=stream)
