"""The label-free price "knee": each clip's number of gaps at the knee of its exact cost curve."""

import pytest
import torch

from keyin.decode.segmentation import KNEE, best_segmentation, knee_counts, path_cost
from tests.decode.enumeration import INF, cheapest_by_count, outside_the_clip


def test_the_knee_is_the_count_after_which_the_saving_falls_most():
    # gaps 2..5 feasible, savings 6, .5, .3 (then 0): falls 5.5, .2, .3 -> 3 gaps
    assert knee_counts(torch.tensor([[INF, INF, 10.0, 4.0, 3.5, 3.2]])).tolist() == [3]
    # the last gap still saves most: the knee is at the most gaps
    assert knee_counts(torch.tensor([[INF, 9.0, 8.5, 8.0, 1.0]])).tolist() == [4]
    # equal savings: only past the most gaps does the saving fall
    assert knee_counts(torch.tensor([[INF, 9.0, 6.0, 3.0]])).tolist() == [3]
    # the first gap saves most, then little: 2 gaps
    assert knee_counts(torch.tensor([[INF, 8.0, 4.0, 3.0, 2.0]])).tolist() == [2]


def test_a_single_feasible_count_is_taken():
    assert knee_counts(torch.tensor([[INF, INF, INF, 7.0], [INF, INF, 5.0, 4.0]])).tolist() == [3, 3]


def test_knee_segmentation_is_the_exact_best_at_the_knee_count():
    torch.manual_seed(3)
    n_future, max_offset, n_keyframes = 9, 4, 5
    costs = torch.rand(6, n_future, max_offset) * 10
    costs = outside_the_clip(costs)
    total, positions = best_segmentation(costs, n_keyframes, KNEE)
    for b in range(6):
        by_count = cheapest_by_count(costs[b], n_keyframes)
        curve = torch.tensor([[by_count.get(m, (INF,))[0] for m in range(n_keyframes + 1)]])
        count = int(knee_counts(curve))
        assert total[b].item() == pytest.approx(by_count[count][0])
        assert positions[b] == by_count[count][1]
    assert torch.allclose(path_cost(costs, positions), total)


def test_a_price_that_is_neither_a_number_nor_knee_is_refused():
    with pytest.raises(ValueError, match="a number .* or 'knee'"):
        best_segmentation(torch.zeros(1, 4, 4), 2, "elbow")


def test_keyin_reads_keyframes_out_by_the_knee_price_and_refuses_another_word():
    from tests.planning.trained_models import keyframe_module

    module = keyframe_module(discovery="map", map_keyframe_cost=KNEE).reader()
    clips, lengths = torch.rand(3, 7, 3, 16, 16), torch.tensor([6, 6, 4])
    positions = module.discover(clips, lengths)
    assert len(positions) == 3 and all(0 <= p < n for row, n in zip(positions, lengths.tolist()) for p in row)
    assert positions[2][-1] == 3  # a clip that ends inside the window ends on a keyframe
    with pytest.raises(ValueError, match="map_keyframe_cost must be nats per keyframe or 'knee'"):
        keyframe_module(discovery="map", map_keyframe_cost="elbow")
