import math

import pytest

from keyin.eval.f1 import keyframe_scores, tolerant_matches


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
