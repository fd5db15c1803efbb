"""The pixel weights of the image likelihood (keyin/losses/image.py) and every BCE that takes them:
known weights on hand-made clips, and each weighted BCE against a brute-force weighted sum."""

import pytest
import torch
import torch.nn.functional as F

from keyin.decode.segment_costs import interpolation_costs
from keyin.losses.image import changed_pixel_weights, future_pixel_weights, model_pixel_weights
from keyin.losses.soft_keyframe import bce_sum
from keyin.losses.tap import frame_bce
from keyin.models import ConvDecoder, Interpolator


def moving_dot_clip() -> torch.Tensor:
    """(1, 3, 3, 4, 4): grey frames; frame 1 has a dot at (1, 2) in the green channel only (+0.5),
    frame 2 a faint change (+0.05 < threshold) at (3, 3)."""
    clip = torch.full((1, 3, 3, 4, 4), 0.5)
    clip[0, 1, 1, 1, 2] = 1.0
    clip[0, 2, :, 3, 3] = 0.55
    return clip


def test_changed_pixels_get_the_weight_in_every_channel():
    weights = changed_pixel_weights(moving_dot_clip(), weight=20.0, threshold=0.1)
    expected = torch.ones(1, 3, 3, 4, 4)
    expected[0, 1, :, 1, 2] = 20.0  # a change in one channel weighs the pixel's three channels
    assert torch.equal(weights, expected)  # frame 0 is the reference; the faint change stays 1


def test_weight_one_is_the_plain_bce_and_nonpositive_weights_are_refused():
    assert changed_pixel_weights(moving_dot_clip(), 1.0, 0.1) is None
    assert model_pixel_weights(moving_dot_clip(), {}) is None  # hparams from before the weighting
    with pytest.raises(ValueError, match="foreground_weight must be > 0"):
        changed_pixel_weights(moving_dot_clip(), 0.0, 0.1)


def test_future_weights_drop_the_conditioning_frames_and_flatten():
    weights = changed_pixel_weights(moving_dot_clip(), 20.0, 0.1)
    future = future_pixel_weights(weights, n_cond=1)
    assert future.shape == (1, 2, 48) and future.sum() == 2 * 48 + 3 * 19
    assert future_pixel_weights(None, 1) is None


def test_weighted_bce_sum_is_the_weighted_sum_of_pixel_bces():
    generator = torch.Generator().manual_seed(0)
    probs = torch.rand(2, 5, 12, generator=generator, dtype=torch.float64)
    targets = torch.rand(2, 5, 12, generator=generator, dtype=torch.float64)
    weights = 1 + 9 * (torch.rand(2, 5, 12, generator=generator, dtype=torch.float64) > 0.7)
    mask = torch.ones(2, 5, dtype=torch.bool)
    mask[1, 3:] = False
    expected = (F.binary_cross_entropy(probs, targets, reduction="none") * weights).sum(-1) * mask
    assert torch.allclose(bce_sum(probs, targets, mask, weights), expected)


def test_weighted_tap_frame_bce_matches_the_pixelwise_weighted_bce():
    generator = torch.Generator().manual_seed(1)
    logits = torch.randn(2, 3, 4, 4, generator=generator, dtype=torch.float64)
    frames = torch.rand(2, 5, 3, 4, 4, generator=generator, dtype=torch.float64)
    weights = changed_pixel_weights((frames > 0.5).double(), 7.0, 0.1)
    expected = torch.stack([
        torch.stack([
            F.binary_cross_entropy_with_logits(logits[b], frames[b, t], weights[b, t], reduction="sum")
            for t in range(5)
        ]) for b in range(2)
    ])
    assert torch.allclose(frame_bce(logits, frames, weights), expected)


def test_segment_costs_scale_with_uniform_weights():
    torch.manual_seed(0)
    interpolator = Interpolator(8, 3, 0, 16, 1, 16).eval()
    decoder = ConvDecoder(8, 1, 4, 8, norm="none").eval()
    boundary_emb = torch.rand(2, 7, 8)
    frames = (torch.rand(2, 6, 64) > 0.5).float()
    plain = interpolation_costs(interpolator, decoder, boundary_emb, frames)
    doubled = interpolation_costs(interpolator, decoder, boundary_emb, frames, torch.full_like(frames, 2.0))
    finite = plain.isfinite()
    assert torch.equal(finite, doubled.isfinite())
    assert torch.allclose(doubled[finite], 2 * plain[finite])
