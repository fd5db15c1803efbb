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


def brute_force_joint(log_offsets: torch.Tensor, length: int) -> list[int]:
    """Every offset sequence: the best sum of log δ up to the first keyframe that leaves (or M)."""
    n_keys, _, max_offset = log_offsets.shape
    best, best_places = -float("inf"), []
    for offsets in itertools.product(range(1, max_offset + 1), repeat=n_keys):
        place, total, places = 0, 0.0, []
        for t, offset in enumerate(offsets):
            total += float(log_offsets[t, place, offset - 1])
            place += offset
            places.append(place)
            if place > length:
                break
        if total > best + 1e-9:
            best, best_places = total, [p - 1 for p in places if p <= length]
    return best_places


def test_the_joint_readout_is_the_most_likely_offset_path():
    from keyin.decode.offsets import joint_offset_keyframes

    torch.manual_seed(0)
    n_keys, max_offset = 3, 3
    log_offsets = torch.log_softmax(torch.randn(5, n_keys, n_keys * max_offset + 1, max_offset) * 2, -1)
    lengths = torch.tensor([4, 7, 9, 2, 5])
    found = joint_offset_keyframes(log_offsets, lengths)
    assert found == [brute_force_joint(log_offsets[b], int(lengths[b])) for b in range(5)]


def test_offset_log_probs_along_a_path_are_the_chains_logits():
    from tests.planning.trained_models import keyframe_module

    model = keyframe_module(offset_evidence=True).model.eval()
    with torch.no_grad():
        model.predictor.boundary_head.bias.fill_(0.5)
        clips, lengths = torch.rand(2, 7, 3, 16, 16), torch.tensor([6, 4])
        _, keys = model.keyframes(clips, lengths, sample=False, chain="argmax")
        table = model.predictor.offset_log_probs(keys.head_logits, keys.boundary_scores, torch.arange(6) < lengths[:, None])
    place = torch.zeros(2, dtype=torch.long)
    for t in range(keys.offset_logits.shape[1]):  # the argmax chain visits one row of the table per keyframe
        expected = torch.log_softmax(keys.offset_logits[:, t], -1)
        torch.testing.assert_close(table[torch.arange(2), t, place], expected, rtol=1e-5, atol=1e-5)
        place = place + keys.offset_logits[:, t].argmax(-1) + 1


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
