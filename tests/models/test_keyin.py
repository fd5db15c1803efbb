"""KEYIN's whole model (keyin/models/keyin.py): the shapes of its three uses, and that its parts
agree — the posterior forward's keyframes are the predictor's, the argmax video is made of the
frames it interpolated, and planning's keyframe images are the decoded prior keyframes of z."""

import pytest
import torch

from keyin.decode.offsets import offset_keyframes
from keyin.decode.prices import Prices
from keyin.decode.registry import rule_named
from keyin.models import KEYIN
from tests.lit.test_keyframe_teacher import batch, keyframe_module


def model() -> KEYIN:
    return keyframe_module(0.0, offset_evidence=True).eval().model  # 8x8 grey, n_cond 2, N 6, M 3, S 3


def test_the_posterior_forward_has_the_documented_shapes():
    data = batch()
    out = model()(data["frames"], data["future_length"], mode="posterior", sample=False)
    assert out["key_emb"].shape == (3, 3, 8) and out["offset_probs"].shape == (3, 3, 3)
    assert out["frames"].shape == (3, 3, 3, 64) and out["boundary_emb"].shape == (3, 7, 8)
    assert out["attention"].shape == (3, 3, 6) and out["boundary_scores"].shape == (3, 6)
    torch.testing.assert_close(out["offset_probs"].sum(-1), torch.ones(3, 3))


def test_its_keyframes_are_the_ones_the_readout_and_the_decoding_layer_see():
    keyin, data = model(), batch()
    with torch.no_grad():
        out = keyin(data["frames"], data["future_length"], mode="posterior", sample=False)
        _, keys = keyin.keyframes(data["frames"], data["future_length"], mode="posterior", sample=False)
    torch.testing.assert_close(out["offset_probs"], keys.offset_probs)
    expected = offset_keyframes(out["offset_probs"], data["future_length"])
    assert rule_named("offsets")(keyin, data["frames"], data["future_length"]) == expected


def test_the_argmax_video_keeps_the_conditioning_frames_and_shows_the_interpolated_ones():
    keyin, data = model(), batch()
    with torch.no_grad():
        out = keyin(data["frames"], data["future_length"], mode="prior", sample=True)
        video = keyin.argmax_video(data["frames"], out)
    assert video.shape == data["frames"].shape
    torch.testing.assert_close(video[:, :2], data["frames"][:, :2])
    first_offset = int(out["offset_probs"][0, 0].argmax()) + 1  # the first gap's frames come first
    torch.testing.assert_close(video[0, 2 : 2 + first_offset].flatten(1), out["frames"][0, 0, :first_offset])


def test_planning_renders_the_decoded_prior_keyframes_of_given_latents():
    keyin, data = model(), batch()
    z = torch.randn(3, 3, 4)
    with torch.no_grad():
        cond_emb = keyin.encoder(data["frames"][:, :2])
        images = keyin.keyframe_images(cond_emb, z)
        last = keyin.keyframe_images(cond_emb, z, last_only=True)
        keys = keyin.predictor(cond_emb, mode="prior", z=z)
    assert images.shape == (3, 3, 1, 8, 8) and last.shape == (3, 1, 1, 8, 8)
    torch.testing.assert_close(images, torch.sigmoid(keyin.decoder(keys.key_emb)))
    torch.testing.assert_close(last[:, 0], images[:, -1])


def test_the_segmentation_rule_is_map_without_stage_2s_scores():
    keyin, data = model(), batch()
    torch.nn.init.normal_(keyin.predictor.boundary_head.weight, std=3.0, generator=torch.Generator().manual_seed(0))
    frames, lengths = data["frames"], data["future_length"]
    for cost in (0.0, 5.0):
        segmentation = rule_named("segmentation")(keyin, frames, lengths, Prices(cost, boundary_weight=1e3))
        assert segmentation == rule_named("map")(keyin, frames, lengths, Prices(cost, boundary_weight=0.0))
        # the test's premise: at this weight the (non-zero) scores change the map keyframes
        assert rule_named("map")(keyin, frames, lengths, Prices(cost, boundary_weight=1e3)) != segmentation


def test_interpolating_from_the_frames_reads_the_embeddings_delta_selects_and_leaves_the_prior_as_it_was():
    """interpolate_from="frames" (ours): the posterior forward's interpolator reads K̃^e(δ), the δ-weighted
    embeddings of the clip's frames, so L_inter reaches δ but not the keyframe-embedding head; the prior
    forward (no frames to read) keeps reading the predicted K̂."""
    from keyin.models.positions import position_distributions, soft_keyframe_targets

    keyin, data = model(), batch()
    keyin.interpolate_from = "frames"
    clips, lengths = data["frames"], data["future_length"]
    out = keyin(clips, lengths, mode="posterior", sample=False)
    keyframe_pos, _ = position_distributions(out["offset_probs"])
    targets = soft_keyframe_targets(keyframe_pos, lengths, out["future_emb"], normalize=True)
    expected = keyin.interpolate(out["boundary_emb"][:, 0], targets, out["offset_probs"])
    torch.testing.assert_close(out["frames"], expected)
    grads = torch.autograd.grad(out["frames"].sum(), [out["offset_logits"], out["key_emb"]], allow_unused=True)
    assert grads[0] is not None and grads[0].abs().sum() > 0  # δ still learns from the interpolation
    assert grads[1] is None  # K̂ does not reach it: only L_ke trains the keyframe embeddings
    torch.manual_seed(0)
    prior_frames = keyin(clips, lengths, mode="prior", sample=False)
    torch.manual_seed(0)
    keyin.interpolate_from = "predicted"
    torch.testing.assert_close(prior_frames["frames"], keyin(clips, lengths, mode="prior", sample=False)["frames"])
    with pytest.raises(ValueError, match=r"interpolate_from must be one of \('predicted', 'frames'\)"):
        KEYIN(keyin.encoder, keyin.decoder, keyin.interpolator, keyin.predictor, 2, interpolate_from="targets")
