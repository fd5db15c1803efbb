"""The frame autoencoder's loss against the brute force: weights of the whole clips, then the drawn frames."""

import torch

from keyin.lit.frame_autoencoder import FrameAutoencoderModule
from keyin.losses.image import changed_pixel_weights
from keyin.losses.interpolation import autoencoding_bce


def test_the_reconstruction_bce_weighs_each_frame_against_its_clips_first_as_the_whole_clip_weights_do():
    torch.manual_seed(0)
    module = FrameAutoencoderModule(8, 3, 1, 6, 4, True, "group", 1e-3, foreground_weight=20.0)
    clips = (torch.rand(3, 5, 3, 8, 8) > 0.7).float()
    clip, frame = torch.tensor([0, 2, 2, 1]), torch.tensor([4, 0, 3, 1])
    weights = changed_pixel_weights(clips, 20.0, 0.1)[clip, frame]
    frames = clips[clip, frame]
    expected = autoencoding_bce(module.network.decoder(module.network.encoder(frames)), frames, weights)
    bce, logits = module.reconstruction(clips, clip, frame)
    torch.testing.assert_close(bce, expected)
    torch.testing.assert_close(logits, module.network.decoder(module.network.encoder(frames)))

