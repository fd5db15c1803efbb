"""The change-point baseline on synthetic signals with known change points."""

import numpy as np
import pytest
import torch

from keyin.decode.changepoint import ChangepointKeyframes


def moving_dot(turns: list[int], n_frames: int, size: int = 16) -> torch.Tensor:
    """(n_frames, 1, size, size): a one-pixel dot moving one pixel a frame, first right; at each
    frame index in ``turns`` (the vertex) it turns, down, then right again, ..."""
    frames = torch.zeros(n_frames, 1, size, size)
    row, col, direction = 1, 1, 0
    for t in range(n_frames):
        frames[t, 0, row, col] = 1.0
        if t in turns:
            direction = 1 - direction
        row, col = (row, col + 1) if direction == 0 else (row + 1, col)
    return frames


def test_the_centroid_velocity_changes_where_a_moving_object_turns():
    """One conditioning frame, then 12 future frames; the dot turns at clip frames 4 and 8, i.e.
    future positions 3 and 7."""
    clip = moving_dot(turns=[4, 8], n_frames=13)
    finder = ChangepointKeyframes(n_keyframes=6, n_cond=1, penalty=1.0, signal="centroid_velocity", cost="l2")
    assert finder(clip[None], torch.tensor([12])) == [[3, 7]]


def test_differences_change_where_the_intensities_stop_rising():
    brightness = torch.tensor([0.1 * t if t <= 6 else 0.6 - 0.1 * (t - 6) for t in range(11)])
    frames = brightness[None, :, None, None, None].expand(1, 11, 1, 4, 4)  # turns at clip frame 6
    finder = ChangepointKeyframes(n_keyframes=6, n_cond=1, penalty=0.1, signal="differences", cost="l2")
    assert finder(frames, torch.tensor([10])) == [[5]]


def test_pixels_find_a_step_in_the_frames():
    frames = torch.zeros(1, 11, 1, 4, 4)
    frames[0, 6:] = 1.0  # frame 6 of the clip (future position 5) opens a new segment
    finder = ChangepointKeyframes(n_keyframes=6, n_cond=1, penalty=1.0, signal="pixels", cost="l2")
    assert finder(frames, torch.tensor([10])) == [[5]]


def test_only_the_valid_frames_are_read_and_the_penalty_prices_each_change():
    clip = moving_dot(turns=[4, 8], n_frames=13)
    padded = clip.clone()
    padded[7:] = torch.rand(6, 1, 16, 16)  # after 6 valid future frames: noise the model must not see
    finder = ChangepointKeyframes(n_keyframes=6, n_cond=1, penalty=1.0)  # centroid velocity, l2
    assert finder(padded[None], torch.tensor([6])) == [[3]]
    assert ChangepointKeyframes(n_keyframes=6, n_cond=1, penalty=1e6)(clip[None], torch.tensor([12])) == [[]]
    assert ChangepointKeyframes(n_keyframes=1, n_cond=1, penalty=1.0)(clip[None], torch.tensor([12])) == [[3]]


@pytest.mark.parametrize("arguments, message", [
    (dict(signal="optical_flow"), "signal must be one of"), (dict(cost="ar"), "cost must be one of"),
    (dict(penalty=-1.0), "penalty must be >= 0"),
])
def test_bad_settings_are_refused(arguments, message):
    with pytest.raises(ValueError, match=message):
        ChangepointKeyframes(**{**dict(n_keyframes=6, n_cond=1, penalty=1.0), **arguments})
