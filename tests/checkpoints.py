"""Stage-2 checkpoints without training: a smoke-sized KEYIN, its weights as initialised, saved in
the layout keyin-train writes, for tests that need a checkpoint's files and shapes, not its skill."""

from __future__ import annotations

from pathlib import Path

import torch
from hydra import compose, initialize_config_module
from hydra.utils import instantiate
from omegaconf import OmegaConf

from keyin import __version__
from keyin.cli.app import CONFIG_MODULE
from keyin.lit.checkpoints import CONFIG_KEY, STAGE_KEY, VERSION_KEY


def untrained_checkpoint(path: Path, *overrides: str, seed: int = 0) -> Path:
    """``keyin-train scale=smoke overrides...``'s stage-2 checkpoint as it would be before any step."""
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        cfg = compose("train", overrides=["scale=smoke", *overrides])
    torch.manual_seed(seed)
    stage1 = instantiate(cfg.model.interpolator)
    module = instantiate(cfg.model.keyframes, stage1=dict(stage1.hparams))
    module.load_stage1(stage1.state_dict())
    config = {key: OmegaConf.to_container(cfg[key], resolve=True) for key in ("model", "dataset", "scale", "backbone")}
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    torch.save({"state_dict": module.state_dict(), "hyper_parameters": dict(module.hparams), CONFIG_KEY: config,
                STAGE_KEY: module.stage, VERSION_KEY: __version__}, path)
    return path
