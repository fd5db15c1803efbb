"""What training adds to keyin.checkpoints: the run config stored in every checkpoint, atomic
writes, and the check that a resumed checkpoint is this run's model."""

from __future__ import annotations

import io
from pathlib import Path
from typing import Any, Mapping

import lightning as L
import torch
from lightning.pytorch.plugins.io import TorchCheckpointIO

from keyin import __version__
from keyin.checkpoints import (  # noqa: F401  (loading without Lightning lives there; imported from here too)
    BEST, CONFIG_KEY, LAST, PASS_A_CHECKPOINT, STAGE_CHECKPOINTS, STAGE_KEY, VERSION_KEY, best_of, load_checkpoint,
    load_stage1, parameter_shapes, run_checkpoint, saved_model_name,
)
from keyin.errors import CheckpointError
from keyin.io import atomic_write_bytes


class RunConfigInCheckpoint(L.Callback):
    """Stores the run's resolved config and the module's stage in every checkpoint."""

    def __init__(self, config: dict[str, Any]) -> None:
        self.config = config

    def on_save_checkpoint(self, trainer: L.Trainer, module: L.LightningModule, checkpoint: dict) -> None:
        checkpoint[CONFIG_KEY] = self.config
        checkpoint[STAGE_KEY] = module.stage
        checkpoint[VERSION_KEY] = __version__


def warm_start(module: L.LightningModule, path: str | Path) -> None:
    """Copy every weight of the checkpoint ``path`` (``pretrained:<name>`` too) of ``module``'s stage into
    ``module`` before its first step (keyin-train ``init_ckpt=``): a warm start, the optimizer fresh.

    Raises:
        CheckpointError: as :func:`load_checkpoint`, or a checkpoint of other parameter shapes.
    """
    saved = load_checkpoint(path, module.stage)
    if parameter_shapes(saved["state_dict"]) != parameter_shapes(module.state_dict()):
        raise CheckpointError(
            f"init_ckpt={path} holds a model={saved_model_name(saved)} whose parameter shapes differ from this run's; "
            f"warm-start with the model= and scale= it was trained with"
        )
    module.load_state_dict(saved["state_dict"])


class AtomicCheckpointIO(TorchCheckpointIO):
    """Writes each checkpoint next to its destination and renames it into place, so a crash or a
    full disk leaves the previous ``last.ckpt`` whole (Lightning's default may stage the file in
    $TMPDIR and copy it across file systems)."""

    def save_checkpoint(self, checkpoint: dict[str, Any], path: Any, storage_options: Any = None) -> None:
        if storage_options is not None:
            raise TypeError(f"{type(self).__name__} takes no storage_options")
        buffer = io.BytesIO()
        torch.save(checkpoint, buffer)
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        atomic_write_bytes(Path(path), buffer.getvalue())


def check_same_model(
    checkpoint: dict[str, Any], path: Path, module: L.LightningModule, config: Mapping[str, Any]
) -> None:
    """Refuse to resume a checkpoint of another model: another ``model=`` (stage 1 excepted, which
    KEYIN, Jumpy and Static share) or other parameter shapes (other sizes in ``scale=``/``dataset=``)."""
    saved_model = saved_model_name(checkpoint)
    model = config.get("model", {}).get("name")
    if module.stage != "interpolator" and saved_model not in (None, model):
        raise CheckpointError(
            f"{path} holds a model={saved_model} checkpoint but this run trains model={model}; "
            f"resume it with model={saved_model}, or train model={model} in a new run dir"
        )
    if parameter_shapes(checkpoint["state_dict"]) != parameter_shapes(module.state_dict()):
        saved, now = checkpoint.get("hyper_parameters", {}), dict(module.hparams)
        changed = [f"{k}={saved[k]!r} (now {now[k]!r})" for k in saved if k in now and saved[k] != now[k]]
        raise CheckpointError(
            f"{path} holds a model of other sizes ({', '.join(changed) or 'other parameter shapes'}); "
            f"resume with the overrides it was trained with, or start a new run dir"
        )
