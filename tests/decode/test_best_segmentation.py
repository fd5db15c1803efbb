import itertools

import pytest
import torch

from keyin.decode.rules import SegmentationDiscoverer, boundary_keyframes, map_keyframes, with_sequence_ends
from keyin.decode.segment_costs import interpolation_costs
from keyin.decode.segmentation import best_segmentation, path_cost, segmentation_offsets
from keyin.losses.soft_keyframe import IGNORE_OFFSET, offset_teacher_loss
from keyin.models import ConvDecoder, Interpolator
from tests.decode.enumeration import brute_force, cheapest_keyframes, keyframe_sets, outside_the_clip, random_map_inputs


def test_dp_matches_enumeration():
    torch.manual_seed(0)
    n_future, max_offset, n_keyframes = 9, 4, 4
    costs = torch.rand(5, n_future, max_offset) * 10
    costs = outside_the_clip(costs)
    total, positions = best_segmentation(costs, n_keyframes)
    for b in range(5):
        expected_total, expected_positions = brute_force(costs[b], n_keyframes)
        assert total[b].item() == pytest.approx(expected_total)
        assert positions[b] == expected_positions
    assert torch.allclose(path_cost(costs, positions), total)


def test_keyframe_cost_prices_every_segment():
    torch.manual_seed(1)
    n_future, max_offset, n_keyframes = 9, 5, 5
    costs = torch.rand(4, n_future, max_offset) * torch.arange(1, max_offset + 1) ** 2  # long gaps cost more
    costs = outside_the_clip(costs)
    counts = []
    for keyframe_cost in (0.0, 3.0, 100.0):
        total, positions = best_segmentation(costs, n_keyframes, keyframe_cost)
        for b in range(4):
            expected_total, expected_positions = brute_force(costs[b], n_keyframes, keyframe_cost)
            assert total[b].item() == pytest.approx(expected_total)
            assert positions[b] == expected_positions
        counts.append(sum(map(len, positions)))
    assert counts[0] > counts[-1] == 4  # a high price leaves the fewest gaps that cover 9 (two each)


def test_dp_recovers_planted_boundaries():
    n_future, max_offset = 12, 6
    costs = torch.full((1, n_future, max_offset), 5.0)
    for left, right in [(0, 4), (4, 9), (9, 12)]:  # cheap gaps ending at positions 3 and 8
        costs[0, left, right - left - 1] = 0.0
    total, positions = best_segmentation(costs, n_keyframes=4)
    assert positions == [[3, 8]] and total.item() == 0.0


def test_dp_rejects_uncoverable_clip():
    with pytest.raises(ValueError, match="cannot cover"):
        best_segmentation(torch.zeros(1, 10, 3), n_keyframes=3)


def test_interpolation_costs_match_direct_decoding():
    torch.manual_seed(0)
    n_future, max_offset, embed_dim = 6, 3, 8
    interpolator = Interpolator(embed_dim, max_offset, 0, 16, 1, 16).eval()
    decoder = ConvDecoder(8, 1, 4, embed_dim, norm="none").eval()
    boundary_emb = torch.rand(2, n_future + 1, embed_dim)
    frames = (torch.rand(2, n_future, 64) > 0.5).float()
    costs = interpolation_costs(interpolator, decoder, boundary_emb, frames, chunk=5)
    b, a, o = 1, 2, 3
    with torch.no_grad():
        out = interpolator(boundary_emb[b, a][None], boundary_emb[b, a + o][None],
                           torch.nn.functional.one_hot(torch.tensor([o - 1]), max_offset).float())
        logits = decoder(out[0, :o]).flatten(1)
    expected = torch.nn.functional.binary_cross_entropy_with_logits(
        logits, frames[b, a : a + o], reduction="sum")
    assert costs[b, a, o - 1].item() == pytest.approx(expected.item(), rel=1e-5)
    assert torch.isinf(costs[:, 5, 1]).all() and torch.isfinite(costs[:, 5, 0]).all()


def test_segmentation_offsets_teach_the_interior_keyframes_then_leaving_the_clip():
    plain = segmentation_offsets([[3, 8], [1, 5, 9], [], [2, 5]], [12, 12, 6, 12], n_keyframes=3, max_offset=5)
    assert plain[0].tolist() == [4, 5, IGNORE_OFFSET] and plain[1].tolist() == [2, 4, 4]  # interior only
    offsets = segmentation_offsets([[3, 8], [1, 5, 9], [], [2, 5]], [12, 12, 6, 12], 3, 5, leave=True)
    # extended indices 4 and 9, then 13 = just past frame 11 (not the closing gap's 12: the last frame)
    assert offsets[0].tolist() == [4, 5, 4]
    assert offsets[1].tolist() == [2, 4, 4]  # all M keyframes are interior: none is left to leave
    assert offsets[2].tolist() == [IGNORE_OFFSET] * 3  # 6 + 1 frames to leave from K^0 > S = 5
    assert offsets[3].tolist() == [3, 3, IGNORE_OFFSET]  # from extended index 6, leaving takes 7 > S


def test_offset_teacher_loss_is_cross_entropy_on_kept_keyframes():
    logits = torch.randn(2, 3, 5, requires_grad=True)
    targets = torch.tensor([[2, 5, -100], [1, -100, -100]])
    loss = offset_teacher_loss(logits, targets)
    kept = [(0, 0, 1), (0, 1, 4), (1, 0, 0)]
    expected = sum(-torch.log_softmax(logits[b, t], -1)[a] for b, t, a in kept) / len(kept)
    assert loss.item() == pytest.approx(expected.item(), rel=1e-6)
    loss.backward()
    assert logits.grad[0, 2].abs().sum() == 0 and logits.grad[1, 1:].abs().sum() == 0


def brute_force_boundaries(scores: list[float], n_keyframes: int, max_offset: int) -> tuple[float, list[int]]:
    """Enumerate every interior boundary set; score Σ log p + Σ log(1 - p) over positions 0…N-2."""
    n_future = len(scores)
    p = torch.sigmoid(torch.tensor(scores, dtype=torch.float64))
    best = (-float("inf"), [])
    for size in range(n_keyframes):
        for chosen in itertools.combinations(range(n_future - 1), size):
            gaps = [b - a for a, b in zip((-1, *chosen), (*chosen, n_future - 1))]
            if max(gaps) > max_offset:
                continue
            loglik = sum(float(torch.log(p[j] if j in chosen else 1 - p[j])) for j in range(n_future - 1))
            best = max(best, (loglik, list(chosen)))
    return best


def test_boundary_keyframes_are_the_map_boundary_set_under_the_gap_limits():
    torch.manual_seed(3)
    scores = torch.randn(6, 9) * 2
    for n_keyframes, max_offset in ((3, 4), (4, 3), (5, 9)):
        decoded = boundary_keyframes(scores, torch.full((6,), 9), n_keyframes, max_offset)
        for row, positions in zip(scores.tolist(), decoded):
            _, expected = brute_force_boundaries(row, n_keyframes, max_offset)
            assert positions == expected


def test_boundary_keyframes_close_each_clip_at_its_own_length():
    scores = torch.full((2, 10), -5.0)
    scores[:, [2, 7]] = 5.0
    decoded = boundary_keyframes(scores, torch.tensor([10, 5]), n_keyframes=4, max_offset=5)
    assert decoded == [[2, 7], [2]]  # position 7 is padding in the second clip


def test_map_keyframes_minimise_bce_plus_price_minus_boundary_scores():
    n_future, max_offset, n_keyframes = 7, 4, 4
    interpolator, decoder, boundary_emb, frames, scores = random_map_inputs(3, n_future, max_offset, seed=2)
    price, weight = 30.0, 2.0
    decoded = map_keyframes(interpolator, decoder, boundary_emb, frames, torch.full((3,), n_future),
                            n_keyframes, price, scores, weight)
    bce = interpolation_costs(interpolator, decoder, boundary_emb, frames)
    sets = keyframe_sets(n_future, max_offset, n_keyframes)
    for b in range(3):
        assert decoded[b] == cheapest_keyframes(bce[b], scores[b], sets, n_future, price, weight)


def test_map_keyframes_close_each_clip_at_its_own_length():
    torch.manual_seed(4)
    interpolator = Interpolator(8, 4, 0, 16, 1, 16).eval()
    decoder = ConvDecoder(8, 1, 4, 8, norm="none").eval()
    boundary_emb, frames = torch.rand(2, 9, 8), (torch.rand(2, 8, 64) > 0.5).float()
    decoded = map_keyframes(interpolator, decoder, boundary_emb, frames, torch.tensor([8, 5]), 4, 1.0)
    alone = map_keyframes(interpolator, decoder, boundary_emb[1:, :6], frames[1:, :5], torch.tensor([5]), 4, 1.0)
    assert decoded[1] == alone[0] and all(p < 4 for p in decoded[1])


def test_a_sequence_that_ends_inside_the_window_ends_at_a_keyframe():
    ends = with_sequence_ends([[2, 7], [2], [], []], torch.tensor([10, 5, 3, 0]), n_future=10)
    assert ends == [[2, 7], [2, 4], [2], []]  # a full clip was cut by the window; an empty one has no end


def test_segmentation_discoverer_segments_each_clip_within_its_own_frames():
    from keyin.lit.interpolator import InterpolatorModule
    from tests.lit.test_keyframe_teacher import STAGE1

    torch.manual_seed(5)
    stage1 = InterpolatorModule(**STAGE1)
    clips = (torch.rand(2, 8, 1, 8, 8) > 0.7).float()
    discover = SegmentationDiscoverer(stage1, n_keyframes=3)
    both = discover(clips, torch.tensor([6, 4]))
    alone = discover(clips[1:, :6], torch.tensor([4]))
    assert both[1] == alone[0] + [3]  # the same interior keyframes, and the sequence's end inside the window
    assert all(p < 5 for p in both[0])  # the full clip gets interior keyframes only
