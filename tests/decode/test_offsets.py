"""The paper's argmax-offset readout on hand-made offset distributions."""

import torch

from keyin.decode.offsets import offset_keyframes


def one_hot_offsets(offsets: list[list[int]], max_offset: int) -> torch.Tensor:
    """(B, M, S) distributions with all their mass on the given offsets."""
    return torch.nn.functional.one_hot(torch.tensor(offsets) - 1, max_offset).float()


def test_positions_are_the_cumulative_offsets_minus_one():
    probs = one_hot_offsets([[2, 3, 1], [4, 4, 4]], max_offset=4)
    assert offset_keyframes(probs, torch.tensor([10, 12])) == [[1, 4, 5], [3, 7, 11]]


def test_keyframes_past_the_valid_frames_are_dropped():
    probs = one_hot_offsets([[2, 3, 1], [4, 4, 4]], max_offset=4)
    assert offset_keyframes(probs, torch.tensor([5, 8])) == [[1, 4], [3, 7]]


def test_the_argmax_decides_where_mass_is_spread():
    probs = torch.tensor([[[0.2, 0.5, 0.3], [0.6, 0.1, 0.3]]])  # argmax offsets 2, 1
    assert offset_keyframes(probs, torch.tensor([6])) == [[1, 2]]
