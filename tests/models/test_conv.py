"""ConvEncoder / ConvDecoder (paper §3.1, §4)."""

import pytest
import torch
from torch import nn

from keyin.models.conv import ConvDecoder, ConvEncoder, coordinate_planes

WIDTH = 4
EMBED_DIM = 8
IMAGE_CONFIGS = [(32, 1, 3), (64, 3, 4)]  # (image_size, channels, stride-2 blocks)


@pytest.mark.parametrize("image_size, channels, depth", IMAGE_CONFIGS)
@pytest.mark.parametrize("coord_channels", [False, True])
@pytest.mark.parametrize("norm", ["batch", "group", "none"])
def test_round_trip_shapes_with_leading_dims(image_size, channels, depth, coord_channels, norm):
    torch.manual_seed(0)
    encoder = ConvEncoder(image_size, channels, WIDTH, EMBED_DIM, coord_channels, norm)
    decoder = ConvDecoder(image_size, channels, WIDTH, EMBED_DIM, coord_channels, norm)
    frames = torch.rand(2, 3, channels, image_size, image_size)

    embeddings = encoder(frames)
    logits = decoder(embeddings)

    assert embeddings.shape == (2, 3, EMBED_DIM)
    assert embeddings.abs().max() < 1.0
    assert logits.shape == frames.shape
    assert encoder(frames[0, 0]).shape == (EMBED_DIM,)
    assert decoder(embeddings[0, 0]).shape == (channels, image_size, image_size)


@pytest.mark.parametrize("image_size, channels, depth", IMAGE_CONFIGS)
def test_depth_matches_paper(image_size, channels, depth):
    encoder = ConvEncoder(image_size, channels, WIDTH, EMBED_DIM)
    decoder = ConvDecoder(image_size, channels, WIDTH, EMBED_DIM)

    encoder_strided = [m for m in encoder.modules() if isinstance(m, nn.Conv2d) and m.stride == (2, 2)]
    decoder_strided = [
        m for m in decoder.modules() if isinstance(m, nn.ConvTranspose2d) and m.stride == (2, 2)
    ]

    assert len(encoder_strided) == depth
    assert [conv.out_channels for conv in encoder_strided] == [WIDTH * 2**index for index in range(depth)]
    assert len(decoder_strided) == depth
    assert decoder_strided[-1].out_channels == channels
    # Normalisation on all encoder blocks but the first.
    assert sum(isinstance(m, nn.BatchNorm2d) for m in encoder.modules()) == depth - 1


def test_decoder_returns_unbounded_logits():
    torch.manual_seed(0)
    decoder = ConvDecoder(32, 1, WIDTH, EMBED_DIM)
    with torch.no_grad():
        decoder.upsampling[-1][0].weight.mul_(100.0)

    logits = decoder(torch.randn(4, EMBED_DIM))

    assert (logits < 0).any()
    assert (logits > 1).any()


@pytest.mark.parametrize("image_size, channels, depth", IMAGE_CONFIGS)
def test_coord_channels_widen_only_the_expected_convs(image_size, channels, depth):
    plain = ConvEncoder(image_size, channels, WIDTH, EMBED_DIM).state_dict()
    coord = ConvEncoder(image_size, channels, WIDTH, EMBED_DIM, coord_channels=True).state_dict()
    changed = {name for name in plain if plain[name].shape != coord[name].shape}
    assert changed == {"blocks.0.weight"}
    assert coord["blocks.0.weight"].numel() - plain["blocks.0.weight"].numel() == 2 * WIDTH * 4 * 4

    plain = ConvDecoder(image_size, channels, WIDTH, EMBED_DIM).state_dict()
    coord = ConvDecoder(image_size, channels, WIDTH, EMBED_DIM, coord_channels=True).state_dict()
    changed = {name for name in plain if plain[name].shape != coord[name].shape}
    assert changed == {f"upsampling.{index}.0.weight" for index in range(depth)}
    for name in changed:  # ConvTranspose2d weights are (in, out, k, k): two more input channels.
        assert coord[name].shape[0] == plain[name].shape[0] + 2
        assert coord[name].shape[1:] == plain[name].shape[1:]


def test_coordinate_planes_hold_x_then_y():
    planes = coordinate_planes(4, torch.zeros(1))

    assert planes.shape == (1, 2, 4, 4)
    torch.testing.assert_close(planes[0, 0, 2], torch.linspace(-1, 1, 4))  # x varies along W
    torch.testing.assert_close(planes[0, 1, :, 2], torch.linspace(-1, 1, 4))  # y varies along H


def test_coord_channels_make_embedding_depend_on_position_of_a_blank_image():
    torch.manual_seed(0)
    encoder = ConvEncoder(32, 1, WIDTH, EMBED_DIM, coord_channels=True, norm="none")
    with torch.no_grad():
        encoder.blocks[0].weight[:, 0].zero_()  # ignore the image: only the coordinates remain

    embeddings = encoder(torch.zeros(1, 1, 32, 32))

    assert embeddings.abs().sum() > 0


def test_decoder_reads_coordinate_planes_before_every_upsampling_conv():
    torch.manual_seed(0)
    decoder = ConvDecoder(32, 1, WIDTH, EMBED_DIM, coord_channels=True, norm="none")
    embeddings = torch.randn(2, EMBED_DIM)
    reference = decoder(embeddings)

    for block in decoder.upsampling:
        with torch.no_grad():
            original = block[0].weight.clone()
            block[0].weight[-2:].zero_()  # the two coordinate input channels
            changed = decoder(embeddings)
            block[0].weight.copy_(original)
        assert not torch.allclose(changed, reference)


@pytest.mark.parametrize("width", [4, 6, 12])
def test_group_norm_groups_divide_small_widths(width):
    encoder = ConvEncoder(32, 1, width, EMBED_DIM, norm="group")
    group_norms = [m for m in encoder.modules() if isinstance(m, nn.GroupNorm)]

    assert len(group_norms) == 2
    for layer in group_norms:
        assert layer.num_groups <= 8 and layer.num_channels % layer.num_groups == 0
    encoder(torch.rand(2, 1, 32, 32))


def test_eval_mode_single_sample_equals_batch_row():
    """Planning runs one sample in eval mode (BatchNorm on a batch of one)."""
    torch.manual_seed(0)
    encoder = ConvEncoder(32, 1, WIDTH, EMBED_DIM)
    decoder = ConvDecoder(32, 1, WIDTH, EMBED_DIM)
    frames = torch.rand(5, 1, 32, 32)
    encoder(frames)  # one train-mode step moves the running statistics away from their init
    encoder.eval()
    decoder.eval()

    torch.testing.assert_close(encoder(frames[:1]), encoder(frames)[:1])
    torch.testing.assert_close(decoder(encoder(frames[:1])), decoder(encoder(frames))[:1])


@pytest.mark.parametrize("image_size, channels, depth", IMAGE_CONFIGS)
@pytest.mark.parametrize("coord_channels", [False, True])
@pytest.mark.parametrize("norm", ["batch", "group", "none"])
def test_eval_mode_decodes_the_same_logits_and_gradients_as_the_plain_path(image_size, channels, depth, coord_channels, norm):
    """Eval mode's faster upsampling (channels_last, the coordinate planes as a bias) against the
    plain concatenating path of the same weights, values and the gradient to the embeddings."""
    torch.manual_seed(0)
    decoder = ConvDecoder(image_size, channels, WIDTH, EMBED_DIM, coord_channels, norm)
    decoder(torch.randn(6, EMBED_DIM))  # one train-mode call moves batch norm's running statistics
    decoder.eval()
    eval_path, calls = decoder._upsample_eval, []
    decoder._upsample_eval = lambda features: calls.append(len(features)) or eval_path(features)
    embeddings = torch.randn(3, 2, EMBED_DIM, requires_grad=True)
    fast = decoder(embeddings)
    assert calls == [6]  # eval mode took the eval path
    plain = decoder._upsample(decoder.head(embeddings.reshape(6, EMBED_DIM, 1, 1)), None).reshape_as(fast)
    torch.testing.assert_close(fast, plain, atol=1e-5, rtol=1e-5)
    assert fast.is_contiguous() and fast.shape == (3, 2, channels, image_size, image_size)
    weights = torch.randn_like(fast)
    (fast_grad,) = torch.autograd.grad((fast * weights).sum(), embeddings)
    (plain_grad,) = torch.autograd.grad((plain * weights).sum(), embeddings)
    torch.testing.assert_close(fast_grad, plain_grad, atol=1e-4, rtol=1e-4)  # sums of more terms: more rounding


@pytest.mark.parametrize("image_size", [0, 4, 16 + 8, 48, 100])
@pytest.mark.parametrize("module", [ConvEncoder, ConvDecoder])
def test_image_size_must_be_power_of_two_at_least_8(image_size, module):
    with pytest.raises(ValueError, match="power of two"):
        module(image_size, 1, WIDTH, EMBED_DIM)


def test_unknown_norm_and_wrong_frame_shape_raise():
    with pytest.raises(ValueError, match="norm"):
        ConvEncoder(32, 1, WIDTH, EMBED_DIM, norm="layer")
    with pytest.raises(ValueError, match="norm"):
        ConvDecoder(32, 1, WIDTH, EMBED_DIM, norm="layer")
    with pytest.raises(ValueError, match="expected frames"):
        ConvEncoder(32, 1, WIDTH, EMBED_DIM)(torch.rand(2, 3, 32, 32))


def test_smallest_image_size_has_one_block():
    encoder = ConvEncoder(8, 1, WIDTH, EMBED_DIM, coord_channels=True)
    decoder = ConvDecoder(8, 1, WIDTH, EMBED_DIM, coord_channels=True)

    assert decoder(encoder(torch.rand(2, 1, 8, 8))).shape == (2, 1, 8, 8)


@pytest.mark.parametrize("image_size, channels, depth", IMAGE_CONFIGS)
def test_skip_features_are_each_blocks_output_finest_first(image_size, channels, depth):
    torch.manual_seed(0)
    encoder = ConvEncoder(image_size, channels, WIDTH, EMBED_DIM, coord_channels=True, norm="group")
    frames = torch.rand(2, 3, channels, image_size, image_size)
    embeddings, skips = encoder.embed_with_skips(frames)
    torch.testing.assert_close(embeddings, encoder(frames))
    assert [tuple(skip.shape) for skip in skips] == [
        (2, 3, WIDTH * 2**index, image_size // 2 ** (index + 1), image_size // 2 ** (index + 1)) for index in range(depth)
    ]


@pytest.mark.parametrize("image_size, channels, depth", IMAGE_CONFIGS)
def test_a_skip_decoder_reads_the_encoder_features_of_each_resolution(image_size, channels, depth):
    torch.manual_seed(0)
    encoder = ConvEncoder(image_size, channels, WIDTH, EMBED_DIM, norm="none")
    decoder = ConvDecoder(image_size, channels, WIDTH, EMBED_DIM, norm="none", skips=True)
    frames = torch.rand(2, 3, channels, image_size, image_size)
    embeddings, skips = encoder.embed_with_skips(frames)

    logits = decoder(embeddings, skips)

    assert logits.shape == frames.shape
    for index in range(depth):  # every level's features reach the output
        changed = [skip.clone() for skip in skips]
        changed[index] = changed[index] + 1.0
        assert not torch.allclose(decoder(embeddings, changed), logits)
    frame = decoder(embeddings[1, 2], [skip[1, 2] for skip in skips])  # no leading dims
    torch.testing.assert_close(frame, logits[1, 2])
    plain = ConvDecoder(image_size, channels, WIDTH, EMBED_DIM, norm="none").state_dict()
    with_skips = decoder.state_dict()
    widened = {name for name in plain if plain[name].shape != with_skips[name].shape}
    assert widened == {f"upsampling.{index}.0.weight" for index in range(depth)}
    for index in range(depth):  # upsampling[k] works at the resolution of encoder block depth-1-k
        name = f"upsampling.{depth - 1 - index}.0.weight"
        assert with_skips[name].shape[0] == plain[name].shape[0] + WIDTH * 2**index


def test_a_decoder_refuses_skips_it_was_not_built_for_and_needs_those_it_was():
    encoder = ConvEncoder(32, 1, WIDTH, EMBED_DIM)
    embeddings, skips = encoder.embed_with_skips(torch.rand(2, 1, 32, 32))
    with pytest.raises(ValueError, match="skips=False"):
        ConvDecoder(32, 1, WIDTH, EMBED_DIM)(embeddings, skips)
    with pytest.raises(ValueError, match="skips=True"):
        ConvDecoder(32, 1, WIDTH, EMBED_DIM, skips=True)(embeddings)
