"""Checkpoints of keyin 0.1 (no version entry) name KEYIN with our additions ``keyin`` and keep
stage 2's networks at the top level; they load under today's name, ``keyin_plus``, into today's
layout, while today's checkpoints keep the name they were saved with."""

import torch

from keyin import __version__
from keyin.lit.checkpoints import CONFIG_KEY, VERSION_KEY, load_trained_module, saved_model_name, upgrade_state_dict
from tests.planning.trained_models import keyframe_module, save


def checkpoint(name: str, version: str | None) -> dict:
    saved = {CONFIG_KEY: {"model": {"name": name}}}
    return saved if version is None else {**saved, VERSION_KEY: version}


def test_a_keyin_0_1_checkpoint_of_keyin_is_keyin_plus():
    assert saved_model_name(checkpoint("keyin", None)) == "keyin_plus"
    assert saved_model_name(checkpoint("jumpy", None)) == "jumpy"


def test_a_checkpoint_with_a_version_keeps_its_name():
    assert saved_model_name(checkpoint("keyin_paper", __version__)) == "keyin_paper"
    assert saved_model_name(checkpoint("keyin", __version__)) == "keyin"


def test_a_keyin_0_1_stage2_checkpoint_loads_into_todays_module(tmp_path):
    """keyin 0.1 kept stage 2's networks at the top of the LightningModule (encoder.*, predictor.*)."""
    module = keyframe_module()
    today = module.state_dict()
    legacy = {name.removeprefix("model."): value for name, value in today.items()}
    assert set(legacy) != set(today) and any(name.startswith("predictor.") for name in legacy)
    path = save(module, tmp_path / "old.ckpt", "keyin")
    checkpoint = torch.load(path, weights_only=True)
    checkpoint["state_dict"] = legacy
    del checkpoint[VERSION_KEY]
    torch.save(checkpoint, path)
    loaded, config = load_trained_module(path)
    assert config["model"]["name"] == "keyin_plus"
    for name, value in today.items():
        torch.testing.assert_close(loaded.state_dict()[name], value, rtol=0, atol=0)
    assert upgrade_state_dict(today) == today  # today's layout is left as it is
