"""The frame autoencoder's loss against the brute force: weights of the whole clips, then the drawn frames."""

import torch

from keyin.lit.frame_autoencoder import FrameAutoencoderModule, valid_frame_index
from keyin.losses.image import changed_pixel_weights
from keyin.losses.interpolation import autoencoding_bce


def test_frame_bce_weighs_each_frame_against_its_clips_first_as_the_whole_clip_weights_do():
    torch.manual_seed(0)
    module = FrameAutoencoderModule(8, 3, 1, 6, 4, True, "group", 1e-3, foreground_weight=20.0)
    clips = (torch.rand(3, 5, 3, 8, 8) > 0.7).float()
    clip, frame = torch.tensor([0, 2, 2, 1]), torch.tensor([4, 0, 3, 1])
    weights = changed_pixel_weights(clips, 20.0, 0.1)[clip, frame]
    frames = clips[clip, frame]
    expected = autoencoding_bce(module.network.decoder, frames, module.network.encoder(frames), weights)
    torch.testing.assert_close(module.frame_bce(clips, clip, frame), expected)


def test_valid_frame_index_lists_every_valid_frame_once():
    clip, frame = valid_frame_index(torch.tensor([2, 0, 3]), 4)
    assert list(zip(clip.tolist(), frame.tolist())) == [(0, 0), (0, 1), (2, 0), (2, 1), (2, 2)]
