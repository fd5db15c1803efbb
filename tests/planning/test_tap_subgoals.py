"""TAP's planner (keyin/planning/tap_subgoals.py): 2^d - 1 subgoals in time order from a checkpoint."""

import numpy as np
import pytest
import torch

from keyin.planning.tap_subgoals import TAPSubgoals, bisect_subgoals
from tests.planning.trained_models import SIZE, save, tap_module

THREADS = torch.get_num_threads()


def test_bisection_gives_two_to_the_depth_minus_one_subgoals_in_order():
    midpoint = lambda first, last: (first + last) / 2  # noqa: E731
    assert bisect_subgoals(midpoint, 0.0, 1.0, 0) == []
    assert bisect_subgoals(midpoint, 0.0, 1.0, 1) == [0.5]
    assert bisect_subgoals(midpoint, 0.0, 1.0, 2) == [0.25, 0.5, 0.75]
    assert bisect_subgoals(midpoint, 0.0, 8.0, 3) == [1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]


def test_the_planner_predicts_one_subgoal_at_depth_1_and_three_at_depth_2(tmp_path):
    checkpoint = save(tap_module(), tmp_path / "tap.ckpt", "tap")
    rng = np.random.default_rng(0)
    start, goal = rng.integers(0, 256, (2, SIZE, SIZE, 3), dtype=np.uint8)
    one = TAPSubgoals(checkpoint, "tap", "pushing", "keyin-train model=tap", THREADS, depth=1)(start, goal, None, rng)
    three = TAPSubgoals(checkpoint, "tap", "pushing", "keyin-train model=tap", THREADS, depth=2)(start, goal, None, rng)
    assert one.images.shape == (1, SIZE, SIZE, 3) and three.images.shape == (3, SIZE, SIZE, 3)
    assert one.images.dtype == three.images.dtype == np.uint8 and one.diagnostics == three.diagnostics == {}
    np.testing.assert_array_equal(three.images[1], one.images[0])  # TAP(start, goal) in the middle


def test_depth_must_be_positive(tmp_path):
    with pytest.raises(ValueError, match="planner.tap_depth=0 must be a positive integer"):
        TAPSubgoals(save(tap_module(), tmp_path / "tap.ckpt", "tap"), "tap", "pushing", "keyin-train", THREADS, depth=0)
