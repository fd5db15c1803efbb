import torch

from keyin.decode.baselines import ConstantKeyframes, RandomKeyframes


def test_random_picks_distinct_frames_inside_each_clip_reproducibly():
    lengths = torch.tensor([30, 30, 4, 12])
    picks = RandomKeyframes(6, seed=1)(None, lengths)
    again = RandomKeyframes(6, seed=1)(None, lengths)
    assert picks == again
    for pick, length in zip(picks, lengths.tolist()):
        assert len(pick) == min(6, length) == len(set(pick))
        assert all(0 <= p < length for p in pick)


def test_constant_marks_every_offset_frames():
    assert ConstantKeyframes(6)(None, torch.tensor([30, 13])) == [[5, 11, 17, 23, 29], [5, 11]]
    assert ConstantKeyframes(4, n_keyframes=3)(None, torch.tensor([30, 9])) == [[3, 7, 11], [3, 7]]  # Jumpy's pattern
