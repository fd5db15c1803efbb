"""Checkpoints of keyin 0.1 (no version entry) name KEYIN with our additions ``keyin`` and keep
stage 2's networks at the top level; they load under today's name, ``keyin_plus``, into today's
layout, while today's checkpoints keep the name they were saved with. Surprise checkpoints from
before its SVG model keep its networks at the top level too, and load into today's layout."""

import lightning as L
import torch
from torch.utils.data import DataLoader

from keyin import __version__
from keyin.lit.checkpoints import CONFIG_KEY, VERSION_KEY, saved_model_name
from keyin.legacy import upgrade_state_dict
from keyin.lit.registry import load_trained_module
from keyin.lit.surprise import SurpriseModule
from tests.planning.trained_models import SIZE, keyframe_module, save, surprise_module


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
    assert upgrade_state_dict(today, "keyframes") == today  # today's layout is left as it is


def surprise_clips() -> list[dict[str, torch.Tensor]]:
    """Four clips of 1 + 6 frames for :func:`tests.planning.trained_models.surprise_module`."""
    frames = torch.rand(4, 7, 3, SIZE, SIZE, generator=torch.Generator().manual_seed(0))
    keyframes = torch.tensor([False, True, False, False, True, False])
    return [{"frames": clip, "future_length": torch.tensor(6), "keyframes": keyframes} for clip in frames]


def before_the_svg_model(path) -> str:
    """The Surprise checkpoint at ``path`` rewritten in the layout from before its SVG model:
    encoder.*, decoder.*, core.* at the top of the LightningModule."""
    checkpoint = torch.load(path, weights_only=True)
    checkpoint["state_dict"] = {name.removeprefix("model."): value for name, value in checkpoint["state_dict"].items()}
    assert any(name.startswith("core.") for name in checkpoint["state_dict"])
    torch.save(checkpoint, path)
    return str(path)


def test_a_surprise_checkpoint_from_before_the_svg_model_loads_with_the_same_outputs(tmp_path):
    module = surprise_module(skips=True).eval()
    loaded, _ = load_trained_module(before_the_svg_model(save(module, tmp_path / "old.ckpt", "surprise")), "surprise")
    assert set(loaded.state_dict()) == set(module.state_dict())
    clips = torch.stack([clip["frames"] for clip in surprise_clips()])
    for output in ("surprise", "one_step_video"):
        expected = getattr(module.model, output)(clips)
        torch.testing.assert_close(getattr(loaded.model, output)(clips), expected, rtol=0, atol=0)
    today = module.state_dict()
    assert upgrade_state_dict(today, "surprise") == today  # today's layout is left as it is


def test_lightning_resumes_a_surprise_checkpoint_from_before_the_svg_model(tmp_path):
    """``SurpriseModule.on_load_checkpoint`` renames the old layout when Lightning restores it."""
    trainer = L.Trainer(accelerator="cpu", logger=False, enable_progress_bar=False, enable_model_summary=False)
    loader = DataLoader(surprise_clips(), batch_size=4)
    module = surprise_module()
    (expected,) = trainer.validate(module, loader, verbose=False)
    trainer.save_checkpoint(tmp_path / "old.ckpt")
    torch.manual_seed(1)  # other initial weights, replaced by the checkpoint's
    (restored,) = trainer.validate(
        SurpriseModule(**module.hparams), loader, ckpt_path=before_the_svg_model(tmp_path / "old.ckpt"), verbose=False
    )
    assert restored == expected


def test_statics_offset_logits_saved_before_the_offset_heads_load_under_their_new_name():
    logits = torch.randn(6, 10)
    for saved in ("model.predictor.static_offset_logits", "predictor.static_offset_logits"):  # 0.2, and 0.1's layout
        upgraded = upgrade_state_dict({saved: logits, "model.predictor.key_head.bias": torch.zeros(3)}, "keyframes")
        assert set(upgraded) == {"model.predictor.offset_head.logits", "model.predictor.key_head.bias"}
        assert upgraded["model.predictor.offset_head.logits"] is logits
