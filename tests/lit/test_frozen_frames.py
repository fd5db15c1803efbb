"""Stage 1 on a frozen frame autoencoder (backbone=frames): its encoder and decoder are the
autoencoder's, stay unchanged by training, and only the interpolator learns."""

import pytest
import torch

from keyin.cli.checks import check_frozen_frames
from keyin.errors import CheckpointError, ConfigError
from keyin.lit.frame_autoencoder import FrameAutoencoderModule
from keyin.lit.interpolator import InterpolatorModule
from tests.lit.test_keyframe_teacher import STAGE1
from tests.lit.test_padding import padded_batches


def autoencoder_checkpoint(**sizes) -> dict:
    """A frame autoencoder's checkpoint content with STAGE1's sizes (or ``sizes``)."""
    torch.manual_seed(3)
    hp = {key: STAGE1[key] for key in ("image_size", "channels", "n_cond", "embed_dim", "conv_width", "coord_channels", "norm")}
    module = FrameAutoencoderModule(**{**hp, **sizes}, lr=1e-3)
    return {"hyper_parameters": dict(module.hparams), "state_dict": module.state_dict()}


def test_a_training_step_moves_the_interpolator_and_leaves_the_autoencoders_networks_as_loaded():
    checkpoint = autoencoder_checkpoint()
    torch.manual_seed(0)
    module = InterpolatorModule(**STAGE1, frozen_frames=True)
    module.load_frame_model(checkpoint, "ae.ckpt")
    module.log_dict = lambda *args, **kwargs: None
    optimizer = module.configure_optimizers()
    interpolator_before = {k: v.clone() for k, v in module.interpolator.state_dict().items()}
    module.train()
    assert not module.encoder.training and not module.decoder.training
    optimizer.zero_grad()
    module.training_step(padded_batches()[0], 0).backward()
    optimizer.step()
    assert all(p.grad is None for p in [*module.encoder.parameters(), *module.decoder.parameters()])
    for name in ("encoder", "decoder"):
        for key, value in getattr(module, name).state_dict().items():
            assert torch.equal(value, checkpoint["state_dict"][f"network.{name}.{key}"]), (name, key)
    assert any(not torch.equal(v, interpolator_before[k]) for k, v in module.interpolator.state_dict().items())


def test_frozen_frames_drop_exactly_the_autoencoding_term():
    torch.manual_seed(0)
    module = InterpolatorModule(**STAGE1)
    logged = {}
    module.log_dict = lambda values, **kwargs: logged.update(values)
    batch = padded_batches()[0]
    module.segment_rng.manual_seed(0)
    joint = module.training_step(batch, 0)
    autoencoding_per_frame = float(logged.pop("train/ae_per_frame").detach())
    module.hparams.frozen_frames = True
    module.segment_rng.manual_seed(0)
    frozen = module.training_step(batch, 0)
    assert "train/ae_per_frame" not in logged
    valid_frames = int((STAGE1["n_cond"] + batch["future_length"]).sum())
    n_clips = len(batch["frames"])
    expected = STAGE1["ae_weight"] * autoencoding_per_frame * valid_frames / n_clips
    assert float((joint - frozen).detach()) == pytest.approx(expected, rel=1e-5) and expected > 0


def test_an_autoencoder_of_other_sizes_is_refused_with_the_sizes_that_differ():
    module = InterpolatorModule(**STAGE1, frozen_frames=True)
    with pytest.raises(CheckpointError, match=r"conv_width=8 \(stage 1: 4\).*backbone=ours"):
        module.load_frame_model(autoencoder_checkpoint(conv_width=8), "ae.ckpt")


@pytest.mark.parametrize("model, stage, frames_ckpt, refused", [
    ({"name": "jumpy", "trainable": True}, "both", "ae.ckpt", None),
    ({"name": "jumpy", "trainable": True}, "both", None, "needs backbone.frames_ckpt="),
    ({"name": "jumpy", "trainable": True}, "keyframes", None, None),  # stage 2 reads stage 1's checkpoint
    ({"name": "tap", "trainable": True, "module": {}}, "both", "ae.ckpt", "model=tap has no stage 1"),
    ({"name": "constant", "trainable": False}, "both", "ae.ckpt", None),  # uses no frame model: one sweep, every row
])
def test_backbone_frames_serves_two_stage_models_and_untrained_baselines(model, stage, frames_ckpt, refused):
    cfg = {"model": model, "stage": stage, "backbone": {"frozen_frames": True, "frames_ckpt": frames_ckpt}}
    if refused is None:
        check_frozen_frames(cfg)
    else:
        with pytest.raises(ConfigError, match=refused):
            check_frozen_frames(cfg)
