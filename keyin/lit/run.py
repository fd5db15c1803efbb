"""Fit one training stage into a run dir: checkpoints, resume, config in checkpoint, NaN guard."""

from __future__ import annotations

import logging
import math
import time
import warnings
from pathlib import Path
from typing import Any, Callable, Mapping, NamedTuple, Sequence

import lightning as L
import torch
from lightning.pytorch.callbacks import ModelCheckpoint

from keyin.errors import KeyinError
from keyin.io import remove_stale_temporaries
from keyin.lit.checkpoints import BEST, AtomicCheckpointIO, RunConfigInCheckpoint, check_same_model, load_checkpoint
from keyin.lit.pictures import ValidationPictures
from keyin.lit.progress import step_progress
from keyin.lit.ranks import RankSeeds


log = logging.getLogger(__name__)

LEARNING_RATES = {
    "interpolator": "scale.lr_stage1", "keyframes": "scale.lr_stage2", "surprise": "scale.lr_surprise", "tap": "scale.lr_tap",
    "frames": "scale.lr_frames",
}


class FiniteLoss(L.Callback):
    """Stop at the first non-finite loss, before a checkpoint of that step is written: the last
    checkpoint on disk stays the last good one."""

    def on_train_batch_end(self, trainer: L.Trainer, module, outputs, batch, batch_idx: int) -> None:
        loss = outputs["loss"] if isinstance(outputs, Mapping) else outputs
        if not math.isfinite(float(loss)):
            last = Path(trainer.default_root_dir) / "checkpoints" / module.stage / "last.ckpt"
            kept = f"the last good checkpoint is {last}" if last.is_file() else "no checkpoint was saved before it"
            raise KeyinError(
                f"non-finite loss {float(loss)} at step {trainer.global_step}, batch {batch_idx}; {kept}; "
                f"lower the learning rate ({LEARNING_RATES.get(module.stage, 'lr')}=...) and run the same "
                f"command again"
            )


class TrainingTime(L.Callback):
    """The wall seconds a stage has trained (validation included), summed over every run that resumed it: kept in
    its checkpoints (``callbacks["TrainingTime"]["seconds"]``), so a job stopped and resumed reports its whole time."""

    def __init__(self, clock: Callable[[], float] = time.perf_counter) -> None:
        self.clock = clock
        self.earlier = 0.0  # the runs before this one, from the checkpoint it resumed
        self.started: float | None = None

    @property
    def seconds(self) -> float:
        return self.earlier + (0.0 if self.started is None else self.clock() - self.started)

    def on_train_start(self, trainer: L.Trainer, module: L.LightningModule) -> None:
        self.started = self.clock()

    def on_train_end(self, trainer: L.Trainer, module: L.LightningModule) -> None:
        self.earlier, self.started = self.seconds, None  # stopped: the final checkpoint and the caller read the same

    def state_dict(self) -> dict[str, float]:
        return {"seconds": self.seconds}

    def load_state_dict(self, state_dict: dict[str, float]) -> None:
        self.earlier = float(state_dict["seconds"])


def training_seconds(checkpoint: Mapping[str, Any]) -> float:
    """The seconds :class:`TrainingTime` kept in a loaded checkpoint; 0 for a checkpoint older than it."""
    return float(checkpoint.get("callbacks", {}).get("TrainingTime", {}).get("seconds", 0.0))


class StageFit(NamedTuple):
    """What :func:`fit_stage` leaves."""

    last: Path  # the stage's last checkpoint
    seconds: float  # wall seconds the stage has trained, over every run of it (:class:`TrainingTime`)
    trained: bool  # whether this call trained it (False: it had its steps already and was only loaded)


class FinalCheckpoint(L.Callback):
    """Save the full final state (optimizer too) to ``path`` when training ends, whatever the checkpoint
    cadence. Saved inside the fit, while its data loader still runs: saved after ``fit`` returns, the
    loader's state would be read from a new worker started only for it, whose shutdown then waits
    5 s (one per stage and worker; docs/decisions.md "The final checkpoint inside the fit")."""

    def __init__(self, path: Path) -> None:
        self.path = path

    def on_train_end(self, trainer: L.Trainer, module: L.LightningModule) -> None:
        trainer.save_checkpoint(self.path, weights_only=False)


FRAME_NETWORKS = ("encoder", "decoder", "interpolator")  # what the discovery rules call, frame by frame


def compile_in_place(holder: torch.nn.Module, names: Sequence[str] | None = None) -> list[str]:
    """Compile, in place, the networks ``names`` of ``holder`` that it has (all its child networks when
    None) with ``nn.Module.compile``: parameter names, so checkpoints, stay the same; the compiled code is
    built on the first call. Returns the names compiled."""
    children = dict(holder.named_children())
    names = list(children) if names is None else [name for name in names if name in children]
    for name in names:
        children[name].compile()
    return names


def compile_frame_networks(module: L.LightningModule) -> list[str]:
    """Compile the frame networks of a trained module that its discovery rules call (:data:`FRAME_NETWORKS`,
    :func:`compile_in_place`). Returns the names compiled.

    Measured on one CPU thread (benchmarks/results/compile_inference.md): the decoder alone 2.1x,
    the exact segmentation end to end 1.26x, after about 40 s of compiling.
    """
    return compile_in_place(getattr(module, "model", module), FRAME_NETWORKS)


def logging_interval(configured: int, max_steps: int) -> int:
    """Steps between logged training scalars: ``trainer.log_every_n_steps``, or a tenth of a shorter
    stage's steps (every step of a stage under 20 steps), so that every stage's curves reach the loggers."""
    return max(1, min(configured, max_steps // 10))


def stage_checkpoints(folder: Path, module: L.LightningModule, checkpoint_every: int) -> list[ModelCheckpoint]:
    """``last.ckpt`` every ``checkpoint_every`` steps, and ``best.ckpt`` at the validation that scored best
    by the module's ``monitor`` (name, "min" or "max"), in ``folder``. Both overwrite their file: a run resumed from a
    ``last.ckpt`` another folder wrote (a copied or extended run) would otherwise save beside it as ``last-v1.ckpt``."""
    monitor, mode = module.monitor
    return [
        ModelCheckpoint(dirpath=folder, save_last=True, save_top_k=0, every_n_train_steps=checkpoint_every,
                        enable_version_counter=False),
        ModelCheckpoint(dirpath=folder, filename=BEST, monitor=monitor, mode=mode, save_top_k=1,
                        auto_insert_metric_name=False, enable_version_counter=False),
    ]


def fit_stage(
    module: L.LightningModule,
    datamodule: L.LightningDataModule,
    run_dir: Path,
    max_steps: int,
    val_every: int,
    checkpoint_every: int,
    trainer_kwargs: Mapping[str, Any],
    logger: Any,
    config: dict[str, Any],
    compile_networks: bool = False,
) -> StageFit:
    """Train ``module`` to ``max_steps``, resuming from ``checkpoints/<stage>/last.ckpt`` if present;
    a stage that has reached ``max_steps`` already is only loaded (its file keeps its bytes and hash).
    Beside ``last.ckpt`` the stage keeps ``best.ckpt`` (:func:`stage_checkpoints`).

    ``compile_networks`` compiles each of the module's networks in place (:func:`compile_in_place`).

    Returns:
        The stage's last checkpoint, its training time over all its runs, and whether this call trained it.
    """
    if compile_networks:
        compile_in_place(module)
    folder = Path(run_dir) / "checkpoints" / module.stage
    last = folder / "last.ckpt"
    trainer_kwargs = dict(trainer_kwargs)
    trainer_kwargs["log_every_n_steps"] = logging_interval(trainer_kwargs.get("log_every_n_steps", 50), max_steps)
    progress = [step_progress()] if trainer_kwargs.get("enable_progress_bar", True) else []
    timer = TrainingTime()
    trainer = L.Trainer(
        **trainer_kwargs,
        max_steps=max_steps,
        val_check_interval=val_every,
        check_val_every_n_epoch=None,
        logger=logger,
        callbacks=[*stage_checkpoints(folder, module, checkpoint_every), RunConfigInCheckpoint(config), FiniteLoss(),
                   ValidationPictures(Path(run_dir) / "pictures"), timer, FinalCheckpoint(last), RankSeeds(config.get("seed", 0)),
                   *progress],
        default_root_dir=str(run_dir),
        plugins=[AtomicCheckpointIO()],
    )
    remove_stale_temporaries(folder)  # a checkpoint being written when the last run was killed
    resume = last if last.is_file() else None
    if resume is not None:  # one clear error for a foreign, corrupt, unsafe or other model's file
        saved = load_checkpoint(resume, module.stage)
        check_same_model(saved, resume, module, config)
        if 0 <= max_steps <= saved.get("global_step", 0):  # finished: its weights, and its file left as it is
            log.info("%s: %s has its %d steps; loaded, not trained again", module.stage, resume, max_steps)
            module.load_state_dict(saved["state_dict"])
            return StageFit(last, training_seconds(saved), trained=False)
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r"Checkpoint directory .* exists and is not empty")  # resumed here by design
        frozen = getattr(module, "frozen_by_design", None)
        if frozen:  # frozen networks are in eval mode by design: said once, in our words
            warnings.filterwarnings("ignore", message=r"Found \d+ module\(s\) in eval mode")
            log.info("%s stay frozen in eval mode (by design)", frozen)
        # weights_only: resuming unpickles nothing but tensors and primitives (a checkpoint cannot run code).
        trainer.fit(module, datamodule=datamodule, ckpt_path=resume, weights_only=True)
    return StageFit(last, timer.seconds, trained=True)
