"""The TAP module: training pairs stay inside the valid frames, validation uses the whole clip, and
its subgoals are images."""

import pytest
import torch

from keyin.lit.tap import TAPModule
from keyin.losses.tap import pair_autoencoding_bce, pair_images

pytestmark = pytest.mark.filterwarnings("ignore:You are trying to `self.log\\(\\)`")  # steps run without a Trainer here


def module(**overrides) -> TAPModule:
    torch.manual_seed(0)
    sizes = dict(image_size=8, channels=3, n_cond=1, embed_dim=8, conv_width=4, coord_channels=True, norm="group",
                 mlp_hidden=16, lr=1e-3)
    return TAPModule(**(sizes | overrides))


def batch() -> dict[str, torch.Tensor]:
    """Two clips of 1 + 8 frames; the second has 4 valid future frames, then padding."""
    frames = torch.rand(2, 9, 3, 8, 8, generator=torch.Generator().manual_seed(1))
    frames[1, 5:] = frames[1, 4]
    return {"frames": frames, "future_length": torch.tensor([8, 4])}


def test_padding_changes_neither_the_training_nor_the_validation_loss():
    model = module()
    clips = batch()
    changed = dict(clips, frames=clips["frames"].clone())
    changed["frames"][1, 5:] = torch.rand(4, 3, 8, 8)
    for stage in ("train", "val"):
        losses = []
        for inputs in (clips, changed):
            torch.manual_seed(2)  # the same training pairs
            losses.append(model._shared_step(inputs, stage))
        assert torch.equal(losses[0], losses[1]), stage


def test_validation_predicts_between_the_first_and_the_last_valid_frame():
    model = module()
    clips = batch()
    loss, argmin = model.pair_terms(clips["frames"], torch.tensor([9, 5]), torch.tensor([0, 0]), torch.tensor([8, 4]))
    assert loss.shape == argmin.shape == (2,)
    assert 2 <= int(argmin[0]) <= 6 and int(argmin[1]) == 2  # a + 1 < t < b - 1
    torch.manual_seed(3)
    assert torch.equal(model._shared_step(clips, "val"), loss.mean())


def test_subgoals_are_images_and_tap_discovers_no_keyframes():
    model = module()
    start, goal = torch.rand(5, 3, 8, 8), torch.rand(5, 3, 8, 8)
    images = model.subgoal(start, goal)
    assert images.shape == (5, 3, 8, 8) and ((images >= 0) & (images <= 1)).all()
    assert model.training  # the mode is restored
    assert model.discoverers("tap") == {}


@pytest.mark.parametrize("overrides", [{"margin": -1}, {"min_gap": 3}, {"margin": 2, "min_gap": 5}, {"max_gap": 3}])
def test_a_gap_range_without_admissible_frames_is_refused(overrides):
    with pytest.raises(ValueError, match="margin"):
        module(**overrides)


def test_pixel_weights_scale_the_min_over_time_loss():
    """Threshold below 0: every pixel weighs 5, so the validation loss is exactly 5x."""
    model = module()
    weighted = module(foreground_weight=5.0, foreground_threshold=-1.0)
    weighted.log_dict = model.log_dict = lambda *args, **kwargs: None
    plain, five = (m._shared_step(batch(), "val") for m in (model, weighted))
    torch.testing.assert_close(five, 5 * plain)


def test_autoencoding_adds_the_bce_of_start_and_goal_decoded_from_their_embeddings():
    """Validation pairs are (0, last valid): the term is the BCE of frames 0 and 8 / 0 and 4."""
    plain, with_ae = module(), module(ae_weight=0.5)
    for m in (plain, with_ae):
        m.log_dict = lambda *args, **kwargs: None
    clips = batch()
    network = with_ae.network
    expected = []
    for clip, last in zip(clips["frames"], (8, 4)):
        images = clip[[0, last]]
        logits = network.decoder(network.encoder(images[None]).flatten(0, 1))
        expected.append(torch.nn.functional.binary_cross_entropy_with_logits(logits, images, reduction="sum"))
    start, goal = torch.tensor([0, 0]), torch.tensor([8, 4])
    _, reconstruction = network.predict_and_reconstruct(*pair_images(clips["frames"], start, goal))
    torch.testing.assert_close(pair_autoencoding_bce(reconstruction, clips["frames"], start, goal), torch.stack(expected))
    total = with_ae._shared_step(clips, "val")
    torch.testing.assert_close(total, plain._shared_step(clips, "val") + 0.5 * torch.stack(expected).mean())
    total.backward()
    assert next(network.encoder.parameters()).grad.abs().sum() > 0
