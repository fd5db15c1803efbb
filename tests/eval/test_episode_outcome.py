"""How a planning episode ended, on hand-made puck paths round a wall along the x axis."""

import numpy as np
import pytest

from keyin.eval.planning import episode_outcome

WALL = np.array([0.0, 0.0, 0.4, 0.03, 0.0])  # centre, half length 0.4, half thickness 0.03, along x
GOAL = np.array([0.0, 0.5])  # across the wall from every start below (y < 0)
RADIUS = 0.06


def path(*points):
    return np.array(points, dtype=np.float64)


@pytest.mark.parametrize("puck,outcome,crossed", [
    (path([0.0, -0.5], [0.5, -0.3], [0.5, 0.3], [0.05, 0.5]), "success", True),
    (path([0.0, -0.5], [0.01, -0.5], [0.0, -0.52]), "untouched", False),
    (path([0.0, -0.5], [0.5, 0.0], [0.0, 0.45], [0.9, 0.9]), "reached_then_lost", True),
    (path([0.0, -0.5], [0.0, -0.12]), "not_crossed", False),  # pushed straight into the wall
    (path([0.0, -0.5], [0.6, 0.0], [0.7, 0.3]), "crossed_missed", True),
])
def test_each_outcome(puck, outcome, crossed):
    how = episode_outcome(puck, WALL, GOAL, RADIUS, threshold=0.3)
    assert how["outcome"] == outcome and how["crossed_wall"] == crossed


def test_the_numbers():
    puck = path([0.0, -0.5], [0.0, -0.12])  # straight at the wall: the path round it from (0, -0.12)
    how = episode_outcome(puck, WALL, GOAL, RADIUS, threshold=0.3)
    assert how["puck_moved"] == pytest.approx(0.38)
    corner = np.array([0.46, -0.09])  # the inflated box's corner on the start side
    expected = np.linalg.norm(corner - [0.0, -0.12]) + 0.18 + np.linalg.norm(GOAL - [0.46, 0.09])
    assert how["closest_error"] == pytest.approx(expected)
