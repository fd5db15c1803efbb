"""The Surprise module: padded frames never enter its loss, and its keyframes come from its KL."""

import torch

from keyin.decode.surprise import surprise_keyframes
from keyin.lit.surprise import SurpriseModule
from keyin.losses.svg import kl_schedule


def module(**overrides) -> SurpriseModule:
    torch.manual_seed(0)
    return SurpriseModule(
        image_size=8, channels=1, n_cond=2, n_future=6, n_keyframes=3, embed_dim=8, conv_width=4,
        coord_channels=True, norm="group", latent_dim=3, lstm_hidden=16, predictor_layers=1,
        posterior_layers=1, beta=0.1, lr=1e-3, **overrides,
    )


def test_padded_frames_add_nothing_to_the_loss():
    model = module()
    frames = torch.rand(2, 8, 1, 8, 8)
    lengths = torch.tensor([6, 3])
    torch.manual_seed(1)
    bce, kl, valid, _ = model._terms({"frames": frames, "future_length": lengths})
    assert bce.shape == kl.shape == (2, 7)
    assert valid[1].tolist() == [True] * 4 + [False] * 3  # frames 1…4 of 2 + 3 valid
    assert (bce[1, 4:] == 0).all() and (kl[1, 4:] == 0).all() and (bce[0] > 0).all()
    changed = frames.clone()
    changed[1, 5:] = torch.rand(3, 1, 8, 8)  # only padding differs
    torch.manual_seed(1)
    bce_changed, _, _, _ = model._terms({"frames": changed, "future_length": lengths})
    torch.testing.assert_close(bce_changed[1], bce[1])


def test_discovery_is_the_peak_picking_of_the_posterior_kl():
    model = module().eval()
    frames, lengths = torch.rand(3, 8, 1, 8, 8), torch.tensor([6, 6, 4])
    kl = model.model.surprise(frames)
    assert kl.shape == (3, 8) and (kl >= 0).all()
    assert model.discover(frames, lengths) == surprise_keyframes(kl, lengths, 2, 3, shift=-1)
    found = model.discoverers("surprise")["surprise_shift0"](frames, lengths)
    assert found == surprise_keyframes(kl, lengths, 2, 3, shift=0)
    assert all(len(row) == 3 and all(0 <= p < n for p in row) for row, n in zip(found, lengths.tolist()))



def test_the_kl_weight_waits_then_rises_linearly_to_beta():
    weights = [kl_schedule(step, beta=2.0, warmup=100, delay=50) for step in (0, 49, 50, 100, 150, 400)]
    assert weights == [0.0, 0.0, 0.0, 1.0, 2.0, 2.0]
    assert [kl_schedule(step, beta=2.0, warmup=0, delay=0) for step in (0, 7)] == [2.0, 2.0]


def test_pixel_weights_scale_the_prediction_and_autoencoding_bce():
    """Threshold below 0: every pixel weighs 5, so both BCE terms are exactly 5x; the KL is not."""
    frames, lengths = torch.rand(2, 8, 1, 8, 8), torch.tensor([6, 3])
    terms = []
    for weight in (1.0, 5.0):
        model = module(ae_weight=1.0, foreground_weight=weight, foreground_threshold=-1.0)
        torch.manual_seed(1)
        terms.append(model._terms({"frames": frames, "future_length": lengths}))
    (bce, kl, _, ae), (bce5, kl5, _, ae5) = terms
    torch.testing.assert_close(bce5, 5 * bce)
    torch.testing.assert_close(ae5, 5 * ae)
    torch.testing.assert_close(kl5, kl)


def test_with_skips_every_frame_is_decoded_with_the_last_conditioning_frames_features():
    model = module(skips=True).eval().model
    frames = torch.rand(2, 8, 1, 8, 8)
    embeddings, context = model.encode(frames)
    _, skips = model.encoder.embed_with_skips(frames)
    for features, all_frames in zip(context, skips):
        torch.testing.assert_close(features, all_frames[:, 1])  # n_cond = 2: frame 1
    earlier = frames.clone()
    earlier[:, 0] = torch.rand(2, 1, 8, 8)  # another first frame: same context
    for features, again in zip(context, model.encode(earlier)[1]):
        torch.testing.assert_close(features, again)
    one_context = [features[:1] for features in context]  # batch 1 broadcasts over the embeddings
    torch.testing.assert_close(model.decode(embeddings, one_context), model.decode(embeddings, [
        features.expand(2, -1, -1, -1) for features in one_context]))
    assert model.decode(embeddings, context).shape == frames.shape
    assert module(skips=False).model.encode(frames)[1] is None


def test_with_skips_padded_frames_still_add_nothing_to_the_loss():
    model = module(skips=True, ae_weight=1.0)
    frames, lengths = torch.rand(2, 8, 1, 8, 8), torch.tensor([6, 3])
    torch.manual_seed(1)
    bce, _, _, ae = model._terms({"frames": frames, "future_length": lengths})
    changed = frames.clone()
    changed[1, 5:] = torch.rand(3, 1, 8, 8)
    torch.manual_seed(1)
    bce_changed, _, _, ae_changed = model._terms({"frames": changed, "future_length": lengths})
    torch.testing.assert_close(bce_changed, bce)
    torch.testing.assert_close(ae_changed, ae)
