"""Segment helpers follow the device of their inputs (keyin ran on a GPU for the first time 2026-11-24)."""

import torch

from keyin.decode.segment_costs import boundary_segment_costs


def test_boundary_costs_stay_on_the_device_of_the_scores():
    """The meta device stands in for a GPU (segment indices used to be CPU tensors)."""
    costs = boundary_segment_costs(torch.zeros(2, 5, device="meta"), 3)
    assert costs.device.type == "meta" and costs.shape == (2, 5, 3)


def test_windows_cut_from_a_videos_costs_equal_the_windows_own_costs():
    """Brute force: each window's interpolation BCE computed alone, against the rows of the whole
    video's (computed in blocks smaller than the video), for windows inside and past its end."""
    from keyin.decode.segment_costs import interpolation_costs, video_interpolation_costs, window_costs
    from tests.planning.trained_models import keyframe_module

    model = keyframe_module().model.eval()
    n_future = 6
    generator = torch.Generator().manual_seed(3)
    frames = torch.rand(23, 3 * 16 * 16, generator=generator)
    embeddings = model.encoder(frames.view(1, 23, 3, 16, 16))[0]
    video = video_interpolation_costs(model.interpolator, model.decoder, embeddings, frames, block=5)
    assert video.shape == (22, 3) and torch.isinf(video[-1, 1:]).all() and torch.isfinite(video[:-2]).all()
    firsts = torch.tensor([0, 3, 9, 16, 19])
    lengths = (22 - firsts).clamp(max=n_future)  # the last two windows are padded past the video's end
    cut = window_costs(video, firsts, lengths, n_future)
    for row, (first, length) in enumerate(zip(firsts.tolist(), lengths.tolist())):
        alone = interpolation_costs(
            model.interpolator, model.decoder, embeddings[None, first : first + length + 1],
            frames[None, first + 1 : first + length + 1],
        )[0]
        torch.testing.assert_close(cut[row, :length], alone)
        assert torch.isinf(cut[row, length:]).all()


def test_video_costs_refuse_a_video_too_short_and_windows_outside_it():
    import pytest

    from keyin.decode.segment_costs import video_interpolation_costs, window_costs
    from tests.planning.trained_models import keyframe_module

    model = keyframe_module().model.eval()
    with pytest.raises(ValueError, match="T ≥ 2"):
        video_interpolation_costs(model.interpolator, model.decoder, torch.zeros(1, 8), torch.zeros(1, 768))
    with pytest.raises(ValueError, match="inside the video"):
        window_costs(torch.zeros(10, 3), torch.tensor([8]), torch.tensor([4]), 6)


def test_a_segment_cost_is_stage_1s_interpolation_bce_at_z_0():
    """The exact segmentation scores a segment by the path stage 1 trains (one interpolate-and-score
    path): the costs of a batch, to the bit, against interpolation_bce on the clip axis."""
    from keyin.data.segments import all_segments
    from keyin.decode.segment_costs import interpolation_costs
    from keyin.losses.interpolation import interpolation_bce
    from tests.decode.enumeration import random_map_inputs

    interpolator, decoder, boundary_emb, frames, _ = random_map_inputs(2, 7, 3, seed=4)
    weights = torch.rand(frames.shape, generator=torch.Generator().manual_seed(4)) + 0.5
    costs = interpolation_costs(interpolator, decoder, boundary_emb, frames, weights)
    clip_frames = torch.cat([frames[:, :1], frames], dim=1)  # frame 0 (K^0) is never a target
    clip_weights = torch.cat([weights[:, :1], weights], dim=1)
    clip, start, offset = all_segments(2, 0, 7, range(1, 4))
    bce, count, stats = interpolation_bce(interpolator, None, decoder, boundary_emb, clip_frames, clip_weights,
                                          (clip, start, offset), "mean")
    assert stats is None and count.tolist() == offset.tolist()
    assert torch.equal(costs[clip, start, offset - 1], bce)
