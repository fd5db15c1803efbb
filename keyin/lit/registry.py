"""Which LightningModule each stage's checkpoint holds, and loading a trained one."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import lightning as L

from keyin.lit.checkpoints import CONFIG_KEY, STAGE_KEY, load_checkpoint, saved_model_name
from keyin.lit.frame_autoencoder import FrameAutoencoderModule
from keyin.lit.interpolator import InterpolatorModule
from keyin.lit.keyframes import KeyframeModule
from keyin.lit.surprise import SurpriseModule
from keyin.lit.tap import TAPModule

STAGES: dict[str, type[L.LightningModule]] = {
    "interpolator": InterpolatorModule, "keyframes": KeyframeModule, "surprise": SurpriseModule, "tap": TAPModule,
    "frames": FrameAutoencoderModule,
}


def load_trained_module(path: str | Path, stage: str | None = "keyframes") -> tuple[L.LightningModule, dict[str, Any]]:
    """A trained module (in eval mode) and the run config stored with it, its ``model.name`` in this
    version's names (:func:`keyin.lit.checkpoints.saved_model_name`).

    Args:
        path: a checkpoint file or ``pretrained:<name>``.
        stage: one of :data:`STAGES`, or None for whichever the checkpoint holds.
    """
    checkpoint = load_checkpoint(path, stage)
    module = STAGES[checkpoint[STAGE_KEY]](**checkpoint["hyper_parameters"])
    module.load_state_dict(checkpoint["state_dict"])
    config = dict(checkpoint[CONFIG_KEY])
    if "model" in config:
        config["model"] = dict(config["model"], name=saved_model_name(checkpoint))
    return module.eval(), config
