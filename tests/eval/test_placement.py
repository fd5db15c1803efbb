"""The stage-1 gate's object scores on hand-made frames with known puck and pusher places."""

import math

import numpy as np
import pytest
import torch

from keyin.envs.segmentation import PUCK_RGB, PUSHER_RGB
from keyin.eval.placement import object_placement, placement_scores

TABLE = (0.85, 0.85, 0.85)
SIZE = 32


def scene(puck=None, pusher=None, radius=2.5):
    """(3, SIZE, SIZE) float frame: the table, and discs of the objects' colours at (column, row) centres."""
    image = np.tile(np.asarray(TABLE, np.float32), (SIZE, SIZE, 1))
    rows, cols = np.mgrid[0:SIZE, 0:SIZE] + 0.5
    for centre, colour in ((puck, PUCK_RGB), (pusher, PUSHER_RGB)):
        if centre is not None:
            image[(cols - centre[0]) ** 2 + (rows - centre[1]) ** 2 <= radius**2] = colour
    return torch.from_numpy(image).permute(2, 0, 1)


def test_exact_frames_score_perfectly():
    truth = torch.stack([scene((8, 8), (20, 20)), scene((10, 12), (24, 6))])
    scores = placement_scores(truth.clone(), truth)
    for name in ("puck", "pusher"):
        assert scores[name].drawn == 1.0 and scores[name].iou == 1.0 and scores[name].within_2px == 1.0
        assert scores[name].centroid_error_px == pytest.approx(0.0, abs=1e-5)
        assert scores[name].frames == 2


def test_a_shifted_puck_costs_its_shift_and_a_missing_pusher_is_not_drawn():
    truth = torch.stack([scene((8, 8), (20, 20))])
    predicted = torch.stack([scene((11, 12), None)])  # puck moved by (3, 4), pusher gone
    scores = placement_scores(predicted, truth)
    assert scores["puck"].centroid_error_px == pytest.approx(5.0, abs=1e-4)
    assert scores["puck"].drawn == 1.0 and scores["puck"].within_2px == 0.0
    assert scores["puck"].iou < 0.2  # two discs of radius 2.5, 5 px apart, barely overlap
    assert scores["pusher"].drawn == 0.0 and scores["pusher"].within_2px == 0.0
    assert math.isnan(scores["pusher"].centroid_error_px) and scores["pusher"].iou == 0.0


def test_iou_against_counted_pixels_and_frames_without_the_object_are_left_out():
    truth = torch.stack([scene((8.5, 8.5)), scene(None)])  # the second frame shows no puck
    predicted = torch.stack([scene((9.5, 8.5)), scene((20, 20))])
    true_mask = (truth[0].permute(1, 2, 0) - torch.tensor(PUCK_RGB)).norm(dim=-1) < 1e-3
    moved_mask = (predicted[0].permute(1, 2, 0) - torch.tensor(PUCK_RGB)).norm(dim=-1) < 1e-3
    expected = (true_mask & moved_mask).sum() / (true_mask | moved_mask).sum()
    puck = object_placement(predicted.permute(0, 2, 3, 1), truth.permute(0, 2, 3, 1), PUCK_RGB)
    assert puck.frames == 1
    assert puck.iou == pytest.approx(float(expected))
    assert puck.centroid_error_px == pytest.approx(1.0, abs=1e-4) and puck.within_2px == 1.0


def test_mismatched_shapes_are_refused():
    with pytest.raises(ValueError, match=r"\(F, H, W, 3\)"):
        object_placement(torch.zeros(2, 8, 8, 3), torch.zeros(1, 8, 8, 3), PUCK_RGB)
