import math

import numpy as np
import pytest

from keyin.eval.f1 import hausdorff, keyframe_scores, tolerant_matches, video_scores


def test_perfect_prediction():
    scores = keyframe_scores([[3, 9, 20]], [[3, 9, 20]], n_future=30)
    assert scores["f1"] == 1.0 and scores["precision"] == 1.0 and scores["recall"] == 1.0
    assert scores["mean_distance"] == 0.0


def test_empty_predictions_score_zero_and_empty_everything_scores_one():
    assert keyframe_scores([[]], [[4, 8]], n_future=30)["f1"] == 0.0
    assert keyframe_scores([[]], [[]], n_future=30)["f1_macro"] == 1.0
    assert math.isnan(keyframe_scores([[]], [[4]], n_future=30)["mean_distance"])


def test_duplicates_and_out_of_window_predictions_are_dropped():
    scores = keyframe_scores([[4, 4, 4, 30, -1]], [[4, 10]], n_future=30)
    assert scores["precision"] == 1.0 and scores["recall"] == 0.5
    assert scores["f1"] == pytest.approx(2 / 3)


def test_off_by_one_misses_exactly_but_matches_with_tolerance():
    scores = keyframe_scores([[5, 11]], [[4, 10]], n_future=30)
    assert scores["f1"] == 0.0
    assert scores["f1_tol1"] == 1.0
    assert scores["mean_distance"] == 1.0


def test_micro_and_macro_differ_on_uneven_clips():
    scores = keyframe_scores([[1], [2, 3, 4]], [[1], [5, 6, 7]], n_future=30)
    assert scores["f1"] == pytest.approx(2 * 1 / (4 + 4))
    assert scores["f1_macro"] == pytest.approx(0.5)
    assert scores["n_sequences"] == 2


def test_tolerant_matching_is_one_to_one_and_maximal():
    assert tolerant_matches([1, 2], [2, 3], tolerance=1) == 2
    assert tolerant_matches([5], [4, 5, 6], tolerance=1) == 1
    assert tolerant_matches([1, 5], [3], tolerance=1) == 0


def brute_force_hausdorff(a, b, n_future):
    if not a and not b:
        return 0.0
    if not a or not b:
        return float(n_future)
    one_way = lambda xs, ys: max(min(abs(x - y) for y in ys) for x in xs)  # noqa: E731
    return float(max(one_way(a, b), one_way(b, a)))


def test_hausdorff_matches_the_brute_force_on_random_sets():
    rng = np.random.default_rng(0)
    for _ in range(200):
        a = sorted(set(rng.integers(0, 12, rng.integers(0, 5)).tolist()))
        b = sorted(set(rng.integers(0, 12, rng.integers(0, 5)).tolist()))
        assert hausdorff(a, b, 12) == brute_force_hausdorff(a, b, 12)


def test_hausdorff_is_the_mean_over_clips():
    scores = keyframe_scores([[2, 9], [], []], [[3, 9], [4], []], n_future=10)
    assert scores["hausdorff"] == pytest.approx((1 + 10 + 0) / 3)


def test_each_tolerance_is_scored_and_one_is_always_there():
    scores = keyframe_scores([[6, 13]], [[4, 10]], n_future=30, tolerances=(3, 2))
    assert (scores["f1_tol1"], scores["f1_tol2"], scores["f1_tol3"]) == (0.0, 0.5, 1.0)


def test_video_scores_pool_the_clips_of_each_video():
    per_video = video_scores([[1], [2], [5]], [[1], [3], [5]], ["a", "b", "a"], n_future=10)
    assert list(per_video) == ["a", "b"]
    assert per_video["a"]["precision"] == 1.0 and per_video["a"]["n_sequences"] == 2
    assert per_video["b"]["recall"] == 0.0
    with pytest.raises(ValueError, match="2 video names for 3 clips"):
        video_scores([[1], [2], [5]], [[1], [3], [5]], ["a", "b"], n_future=10)
