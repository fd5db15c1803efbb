"""The index arithmetic of imported videos: windows, padding, labels, the split by video, the way back."""

import numpy as np
import pytest

from keyin.data.windows import (
    cut_window,
    kept_keyframes,
    original_frame,
    original_time,
    split_videos,
    window_keyframes,
    window_starts,
)
from keyin.errors import DatasetFormatError


def test_windows_of_stride_n_future_give_each_future_frame_to_one_clip():
    n_cond, n_future = 2, 10
    starts = window_starts(40, n_cond + n_future, n_cond, n_future, min_future=1)
    assert starts == [0, 10, 20, 30]  # the last holds 10 frames: 8 future, padded to 12
    futures = [frame for start in starts for frame in range(start + n_cond, min(start + n_cond + n_future, 40))]
    assert futures == list(range(n_cond, 40))


def test_overlapping_windows_stop_at_the_first_that_reaches_the_end():
    assert window_starts(20, 12, 2, 4, min_future=1) == [0, 4, 8]
    assert window_starts(12, 12, 2, 4, min_future=1) == [0]


def test_a_short_video_is_one_padded_window_and_a_too_short_one_none():
    assert window_starts(5, 12, 2, 10, min_future=1) == [0]
    assert window_starts(2, 12, 2, 10, min_future=1) == []
    assert window_starts(5, 12, 2, 10, min_future=4) == []
    assert window_starts(23, 12, 2, 10, min_future=1) == [0, 10, 20]
    assert window_starts(23, 12, 2, 10, min_future=3) == [0, 10]  # the 3-frame tail has 1 future frame


def test_a_cut_window_repeats_its_last_frame_and_counts_its_valid_frames():
    frames = np.arange(7)[:, None] * np.ones((1, 3))
    window, length = cut_window(frames, 4, 5)
    assert length == 3 and window[:, 0].tolist() == [4, 5, 6, 6, 6]
    window, length = cut_window(frames, 0, 5)
    assert length == 5 and window[:, 0].tolist() == [0, 1, 2, 3, 4]


def test_labels_go_to_the_nearest_kept_frame_a_tie_to_the_earlier():
    assert kept_keyframes([0, 5, 9], 1, 10) == [0, 5, 9]
    assert kept_keyframes([2, 3, 5, 9], 2, 5) == [1, 2, 4]  # 3 lies between kept 2 and 4: kept frame 1 (original 2)
    assert kept_keyframes([4, 5, 8], 3, 3) == [1, 2]  # 8 would be kept frame 3 (original 9), past the last: kept 2


def test_window_keyframes_are_the_labels_inside_the_window_on_its_own_axis():
    assert np.flatnonzero(window_keyframes([1, 12, 15, 30], 10, 12)).tolist() == [2, 5]


@pytest.mark.parametrize("stride", [1, 2])
def test_a_clip_position_maps_back_to_the_original_frame_and_second(stride):
    first_frame = 10 * stride  # the window that starts at kept frame 10
    assert [original_frame(first_frame, stride, p) for p in (0, 1, 5)] == [(10 + p) * stride for p in (0, 1, 5)]
    assert original_time(original_frame(first_frame, stride, 5), fps=10.0) == pytest.approx(1.5 * stride)
    assert original_time(15, None) is None and original_time(15, float("nan")) is None


def test_the_split_is_by_video_seeded_with_every_split_nonempty():
    fractions = {"train": 0.8, "val": 0.1, "test": 0.1}
    splits = split_videos(12, fractions, seed=3)
    assert {name: len(videos) for name, videos in splits.items()} == {"train": 10, "val": 1, "test": 1}
    assert sorted(v for videos in splits.values() for v in videos) == list(range(12))
    assert split_videos(12, fractions, seed=3) == splits
    assert split_videos(12, fractions, seed=4) != splits
    assert {name: len(v) for name, v in split_videos(3, fractions, seed=0).items()} == {"train": 1, "val": 1, "test": 1}
    assert list(split_videos(2, {"train": 1.0, "val": 0.0}, seed=0)) == ["train"]


def test_fewer_videos_than_splits_is_refused_with_the_fix():
    with pytest.raises(DatasetFormatError, match=r"2 video\(s\) cannot be split by video into 3 splits.*fractions="):
        split_videos(2, {"train": 0.8, "val": 0.1, "test": 0.1}, seed=0)
