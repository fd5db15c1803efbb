"""The paper's argmax-offset readout on hand-made offset distributions."""

import itertools

import torch

from keyin.decode.offsets import keyframe_probabilities, offset_keyframes


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
    from keyin.decode.registry import rule_named
    from tests.planning.trained_models import keyframe_module

    model = keyframe_module(offset_evidence=True).model.eval()
    with torch.no_grad():
        model.predictor.boundary_head.bias.fill_(0.5)  # evidence that differs between the chains
        clips, lengths = torch.rand(4, 7, 3, 16, 16), torch.tensor([6, 6, 5, 6])
        found = rule_named("offsets")(model, clips, lengths)
        _, argmax = model.keyframes(clips, lengths, sample=False, chain="argmax")
        _, soft = model.keyframes(clips, lengths, sample=False, chain="soft")
    assert found == offset_keyframes(argmax.offset_probs, lengths)
    assert not torch.allclose(argmax.offset_logits, soft.offset_logits)


def test_keyframe_probabilities_are_those_of_enumerating_every_offset_path():
    torch.manual_seed(0)
    n_keys, max_offset, n_future = 3, 3, 7
    probs = torch.softmax(torch.randn(2, n_keys, max_offset, dtype=torch.float64), -1)
    expected = torch.zeros(2, n_future, dtype=torch.float64)
    for offsets in itertools.product(range(1, max_offset + 1), repeat=n_keys):
        path = torch.stack([probs[:, t, o - 1] for t, o in enumerate(offsets)]).prod(0)  # (B,)
        for position in itertools.accumulate(offsets):  # extended index = position + 1
            if position - 1 < n_future:
                expected[:, position - 1] += path
    assert torch.allclose(keyframe_probabilities(probs, n_future), expected)
    assert float(keyframe_probabilities(probs, n_future).max()) <= 1.0
