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


def test_keyins_offsets_rule_reads_the_evidence_along_its_own_argmax_path():
    from keyin.decode.rules import keyin_keyframes
    from tests.planning.trained_models import keyframe_module

    model = keyframe_module(offset_evidence=True).model.eval()
    with torch.no_grad():
        model.predictor.boundary_head.bias.fill_(0.5)  # evidence that differs between the chains
        clips, lengths = torch.rand(4, 7, 3, 16, 16), torch.tensor([6, 6, 5, 6])
        found = keyin_keyframes(model, clips, lengths, "offsets")
        _, argmax = model.keyframes(clips, lengths, sample=False, chain="argmax")
        _, soft = model.keyframes(clips, lengths, sample=False, chain="soft")
    assert found == offset_keyframes(argmax.offset_probs, lengths)
    assert not torch.allclose(argmax.offset_logits, soft.offset_logits)
