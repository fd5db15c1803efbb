"""Surprise peak picking on hand-made KL curves."""

import torch

from keyin.decode.surprise import peak_indices, surprise_keyframes, surprise_positions


def curve(*values: float) -> torch.Tensor:
    return torch.tensor(values)


def test_peaks_are_strict_local_maxima_and_ends_compare_one_sided():
    assert peak_indices(curve(0, 3, 1, 1, 5, 2)) == [1, 4]
    assert peak_indices(curve(4, 1, 0, 2)) == [0, 3]  # both ends
    assert peak_indices(curve(0, 2, 2, 0)) == []  # a plateau is no peak
    assert peak_indices(curve(1, 1, 1)) == []


def test_the_largest_peaks_win_over_larger_non_peaks():
    scores = curve(0, 5, 9, 8, 0, 3, 0, 4, 0)  # peaks at 2, 5, 7; 3 is large but no peak
    assert surprise_positions(scores, n_keyframes=2, first=0, count=9) == [2, 7]


def test_fewer_peaks_than_keyframes_are_filled_with_the_largest_remaining_steps():
    scores = curve(0, 1, 2, 3, 4, 3.5, 0)  # one peak at 4
    assert surprise_positions(scores, n_keyframes=3, first=0, count=7) == [3, 4, 5]
    assert surprise_positions(curve(2, 2, 2), n_keyframes=5, first=0, count=3) == [0, 1, 2]


def test_the_window_uses_real_neighbours_at_its_edges():
    scores = curve(0, 9, 5, 6, 1, 2)
    # Index 2 is inside the window but smaller than its real left neighbour: not a peak.
    assert surprise_positions(scores, n_keyframes=1, first=2, count=4) == [3]


def test_keyframes_are_shifted_one_frame_back_and_stay_inside_the_clip():
    n_cond, kl = 2, torch.zeros(2, 8)
    kl[0, [3, 6]] = 5.0  # clip indices 3, 6 = future 1, 4: the frames after vertices 0 and 3
    kl[1, 7] = 9.0  # a peak at position 4: beyond clip 1's valid length 4
    kl[1, 4] = 1.0  # a peak at position 1
    shifted = surprise_keyframes(kl, torch.tensor([6, 4]), n_cond, n_keyframes=2, shift=-1)
    assert shifted[0] == [0, 3]
    assert 1 in shifted[1] and all(0 <= p < 4 for p in shifted[1])
    unshifted = surprise_keyframes(kl, torch.tensor([6, 4]), n_cond, n_keyframes=2, shift=0)
    assert unshifted[0] == [1, 4]
