"""Which module each stage's checkpoint holds, and loading a trained one.

A stage-2 checkpoint loads as a :class:`keyin.decode.trained.KeyframeReader` (the model, its rule and
prices), built with torch alone: keyin-eval and keyin-discover on a KEYIN, Jumpy or Static model never import Lightning
(a second or more of every command's start). The other stages load as their LightningModule.
"""

from __future__ import annotations

import importlib
from pathlib import Path
from typing import Any, Callable

import torch
from torch import nn

from keyin.checkpoints import CONFIG_KEY, STAGE_KEY, load_checkpoint, saved_model_name

# stage -> "module:class" of the LightningModule that trains it (imported only when loaded)
STAGES: dict[str, str] = {
    "interpolator": "keyin.lit.interpolator:InterpolatorModule", "keyframes": "keyin.lit.keyframes:KeyframeModule",
    "surprise": "keyin.lit.surprise:SurpriseModule", "tap": "keyin.lit.tap:TAPModule",
    "frames": "keyin.lit.frame_autoencoder:FrameAutoencoderModule",
}


def stage_builder(stage: str) -> Callable[..., nn.Module]:
    """What builds the module a checkpoint of ``stage`` loads as from its hyper-parameters: a stage 2's
    reader without Lightning, else the stage's LightningModule."""
    if stage == "keyframes":
        from keyin.decode.trained import KeyframeReader

        return KeyframeReader.from_hparams
    module, name = STAGES[stage].split(":")
    return getattr(importlib.import_module(module), name)


def run_config(checkpoint: dict[str, Any]) -> dict[str, Any]:
    """The run config stored in a checkpoint, its ``model.name`` in this version's names."""
    config = dict(checkpoint[CONFIG_KEY])
    if "model" in config:
        config["model"] = dict(config["model"], name=saved_model_name(checkpoint))
    return config


def load_trained_module(
    path: str | Path, stage: str | None = "keyframes", device: torch.device | str = "cpu"
) -> tuple[nn.Module, dict[str, Any]]:
    """A trained module (in eval mode, on ``device``) and the run config stored with it, its
    ``model.name`` in this version's names (:func:`keyin.checkpoints.saved_model_name`).

    Args:
        path: a checkpoint file or ``pretrained:<name>``.
        stage: one of :data:`STAGES`, or None for whichever the checkpoint holds.
    """
    checkpoint = load_checkpoint(path, stage)
    module = stage_builder(checkpoint[STAGE_KEY])(**checkpoint["hyper_parameters"])
    module.load_state_dict(checkpoint["state_dict"])
    return module.to(device).eval(), run_config(checkpoint)


def load_training_module(path: str | Path, stage: str | None = "keyframes") -> tuple[nn.Module, dict[str, Any]]:
    """As :func:`load_trained_module`, but as the LightningModule that trains the stage (a stage 2's
    ``soft_loss`` included), in train mode on the CPU: to train on from a checkpoint, or study its loss."""
    checkpoint = load_checkpoint(path, stage)
    module_name, name = STAGES[checkpoint[STAGE_KEY]].split(":")
    module = getattr(importlib.import_module(module_name), name)(**checkpoint["hyper_parameters"])
    module.load_state_dict(checkpoint["state_dict"])
    return module, run_config(checkpoint)
