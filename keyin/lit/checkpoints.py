"""Safe checkpoint loading and the run config that travels inside every checkpoint."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import lightning as L
import torch

from keyin.errors import CheckpointError

CONFIG_KEY = "keyin_config"
STAGE_KEY = "keyin_stage"


class RunConfigInCheckpoint(L.Callback):
    """Stores the run's resolved config and the module's stage in every checkpoint."""

    def __init__(self, config: dict[str, Any]) -> None:
        self.config = config

    def on_save_checkpoint(self, trainer: L.Trainer, module: L.LightningModule, checkpoint: dict) -> None:
        checkpoint[CONFIG_KEY] = self.config
        checkpoint[STAGE_KEY] = module.stage


def load_checkpoint(path: str | Path, stage: str | None = None) -> dict[str, Any]:
    """Load a keyin checkpoint without running any pickled code (``weights_only=True``).

    Args:
        stage: "interpolator" or "keyframes" to insist on; None accepts either.
    Raises:
        CheckpointError: missing file, unsafe or foreign content, or another stage.
    """
    path = Path(path)
    if not path.is_file():
        raise CheckpointError(f"checkpoint {path} does not exist; pass the path of a keyin checkpoint")
    try:
        checkpoint = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as err:  # unpickling refuses anything but tensors and primitives
        raise CheckpointError(
            f"{path} is not a loadable keyin checkpoint ({type(err).__name__}: "
            f"{str(err).splitlines()[0][:200]}); it may be corrupt or carry code, which keyin refuses"
        ) from None
    if not isinstance(checkpoint, dict) or STAGE_KEY not in checkpoint:
        raise CheckpointError(f"{path} is not a keyin checkpoint (no '{STAGE_KEY}' entry)")
    if stage is not None and checkpoint[STAGE_KEY] != stage:
        raise CheckpointError(
            f"{path} is a '{checkpoint[STAGE_KEY]}' checkpoint but a '{stage}' one is needed"
            + (
                "; pass the stage-1 checkpoint (checkpoints/interpolator/last.ckpt)"
                if stage == "interpolator"
                else "; pass a stage-2 checkpoint (checkpoints/keyframes/last.ckpt)"
            )
        )
    return checkpoint


def load_trained_module(path: str | Path, stage: str | None = "keyframes") -> tuple[L.LightningModule, dict[str, Any]]:
    """A trained module of either stage (in eval mode) and the run config stored with it.

    Args:
        stage: "interpolator", "keyframes", or None for whichever the checkpoint holds.
    """
    # The modules import this file's callback, so they are imported here.
    from keyin.lit.interpolator import InterpolatorModule
    from keyin.lit.keyframes import KeyframeModule
    from keyin.lit.surprise import SurpriseModule

    checkpoint = load_checkpoint(path, stage)
    stages = {"interpolator": InterpolatorModule, "keyframes": KeyframeModule, "surprise": SurpriseModule}
    module_class = stages[checkpoint[STAGE_KEY]]
    module = module_class(**checkpoint["hyper_parameters"])
    module.load_state_dict(checkpoint["state_dict"])
    return module.eval(), checkpoint[CONFIG_KEY]
