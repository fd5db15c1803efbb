"""The information rule (docs/evaluation.md) on hand-made clips: in the interior column no method
can score with a sequence's end alone; in the with-ends column every method has it."""

import pytest
import torch

from keyin.eval.discovery import evaluate_discoverer
from keyin.decode.ends import sequence_ends, with_ends
from keyin.eval.f1 import column_scores, keyframe_scores, without_ends

N = 10
# Clip 0 ends inside the window after 6 valid frames (its last valid frame, 5, is a label);
# clip 1 fills the window (its last frame is no event).
TRUTH = [[2, 5], [3, 7]]
LENGTHS = [6, 10]


def test_only_a_clip_that_ends_inside_the_window_has_a_sequence_end():
    assert sequence_ends(LENGTHS, N) == [5, None]
    assert sequence_ends([0, 1], N) == [None, 0]  # an empty clip has none


def test_the_end_is_removed_from_or_added_to_each_clip_once():
    ends = sequence_ends(LENGTHS, N)
    assert without_ends([[5, 2], [9]], ends) == [[2], [9]]
    assert with_ends([[2], [9]], ends) == [[2, 5], [9]] and with_ends([[5, 2], []], ends) == [[2, 5], []]


def test_in_the_interior_column_the_end_alone_scores_nothing():
    end_only = column_scores([[5], []], TRUTH, LENGTHS, N)  # a method that marks just the end
    nothing = column_scores([[], []], TRUTH, LENGTHS, N)
    assert end_only["f1_interior"] == nothing["f1_interior"] == 0.0
    assert keyframe_scores([[5], []], TRUTH, N)["f1"] > 0.0  # scored as given, the end alone pays


def test_in_the_with_ends_column_every_method_has_the_end():
    end_only = column_scores([[5], []], TRUTH, LENGTHS, N)
    nothing = column_scores([[], []], TRUTH, LENGTHS, N)
    assert end_only["f1_with_ends"] == nothing["f1_with_ends"] == pytest.approx(2 * 1 / (1 + 4))
    assert end_only["n_true_with_ends"] == nothing["n_true_with_ends"] == 2.0


def test_full_length_clips_score_the_same_in_every_column():
    predicted, truth = [[3, 6], [1, 7]], [[3, 7], [2, 7]]
    columns = column_scores(predicted, truth, [N, N], N)
    given = keyframe_scores(predicted, truth, N)
    for score in ("f1", "f1_tol1", "precision", "recall", "n_predicted"):
        assert columns[f"{score}_interior"] == columns[f"{score}_with_ends"] == given[score]


def test_a_worked_example():
    """docs/evaluation.md's example: labels {2, 5} in a clip of 6 valid frames, Random-like {1, 2}
    and end-aware {2, 5} predictions."""
    random_like = column_scores([[1, 2]], [[2, 5]], [6], N)
    end_aware = column_scores([[2, 5]], [[2, 5]], [6], N)
    assert (random_like["f1_interior"], end_aware["f1_interior"]) == (pytest.approx(2 / 3), 1.0)
    assert (random_like["f1_with_ends"], end_aware["f1_with_ends"]) == (pytest.approx(0.8), 1.0)


def test_every_scored_method_gets_both_columns():
    keyframes = torch.zeros(2, N, dtype=torch.bool)
    keyframes[0, [2, 5]] = keyframes[1, [3, 7]] = True
    clips = [dict(frames=torch.zeros(11, 1, 8, 8), future_length=torch.tensor(n), keyframes=k)
             for n, k in zip(LENGTHS, keyframes)]

    def end_only(frames, future_length):  # marks each padded clip's last valid frame
        return [[n - 1] if n < N else [] for n in future_length.tolist()]

    scores = evaluate_discoverer(end_only, clips, N)
    assert scores["f1_interior"] == 0.0 and scores["f1"] > 0.0
    assert scores["f1_with_ends"] == evaluate_discoverer(lambda f, n: [[], []], clips, N)["f1_with_ends"]
