"""Shortest path around the inflated wall and the camera homography (REFERENCE §5.2, §7.2)."""

import itertools
import math

import numpy as np
import pytest

from keyin.envs.geometry import (
    apply_homography,
    plane_homography,
    segment_crosses_box,
    shortest_path,
    shortest_path_length,
    to_wall_frame,
    wall_corners,
)

# A horizontal wall at the origin: 0.8 long, 0.06 thick; grown by 0.06 it spans |x| <= 0.46, |y| <= 0.09.
WALL = np.array([0.0, 0.0, 0.4, 0.03, 0.0])
R = 0.06


def perimeter_geodesic(start, goal, wall, inflate):
    """Independent reference for a blocked segment: best pair of visible corners joined along the
    box boundary (exact for one convex obstacle)."""
    corners = wall_corners(wall, inflate)
    visible = lambda p, c: not segment_crosses_box(p, c, wall, inflate)  # noqa: E731
    edges = np.linalg.norm(np.roll(corners, -1, 0) - corners, axis=1)
    best = math.inf
    for i, j in itertools.product(range(4), range(4)):
        if not (visible(start, corners[i]) and visible(goal, corners[j])):
            continue
        forward = sum(edges[(i + k) % 4] for k in range((j - i) % 4))
        along = min(forward, edges.sum() - forward)
        best = min(best, np.linalg.norm(corners[i] - start) + along + np.linalg.norm(goal - corners[j]))
    return best


def test_clear_segment_is_euclidean():
    start, goal = np.array([-0.8, 0.5]), np.array([0.7, 0.2])
    assert shortest_path_length(start, goal, WALL, R) == pytest.approx(np.hypot(1.5, 0.3))


def test_hand_worked_detour():
    # Straight up through the wall centre: round either end, |(0.46, 0.41)| twice plus the 0.18 end.
    length, path = shortest_path(np.array([0.0, -0.5]), np.array([0.0, 0.5]), WALL, R)
    assert length == pytest.approx(2 * np.hypot(0.46, 0.41) + 0.18)
    assert len(path) == 4
    assert np.allclose(np.abs(path[1:3, 0]), 0.46) and np.allclose(np.abs(path[1:3, 1]), 0.09)


def test_asymmetric_detour_takes_the_shorter_end():
    length, path = shortest_path(np.array([0.3, -0.3]), np.array([0.35, 0.3]), WALL, R)
    assert np.all(path[1:-1, 0] > 0)  # round the right end
    assert length == pytest.approx(np.hypot(0.16, 0.21) + 0.18 + np.hypot(0.11, 0.21))


def test_touching_is_not_crossing():
    corners = wall_corners(WALL, R)
    assert not segment_crosses_box(corners[0], corners[1], WALL, R)  # along the top edge
    assert not segment_crosses_box(np.array([-1.0, 0.09]), np.array([1.0, 0.09]), WALL, R)
    assert segment_crosses_box(np.array([-1.0, 0.0]), np.array([1.0, 0.0]), WALL, R)
    assert not segment_crosses_box(np.array([0.47, -1.0]), np.array([0.47, 1.0]), WALL, R)


def test_point_inside_the_inflated_wall_is_pushed_out():
    # 0.01 inside the top face: moved up by 0.01, then a clear straight line.
    length = shortest_path_length(np.array([0.0, 0.08]), np.array([0.0, 0.5]), WALL, R)
    assert length == pytest.approx(0.01 + 0.41)


@pytest.mark.parametrize("seed", range(3))
def test_matches_independent_reference_and_is_rotation_invariant(seed):
    rng = np.random.default_rng(seed)
    for _ in range(40):
        wall = np.array([*rng.uniform(-0.2, 0.2, 2), rng.uniform(0.2, 0.5), 0.03, rng.uniform(-np.pi, np.pi)])
        local = np.array([[rng.uniform(-0.6, 0.6), -rng.uniform(0.15, 0.6)],
                          [rng.uniform(-0.6, 0.6), rng.uniform(0.15, 0.6)]])
        start, goal = wall[:2] + local @ np.array([[np.cos(wall[4]), np.sin(wall[4])],
                                                  [-np.sin(wall[4]), np.cos(wall[4])]])
        length, path = shortest_path(start, goal, wall, R)
        assert not any(segment_crosses_box(a, b, wall, R) for a, b in zip(path[:-1], path[1:]))
        assert np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)) == pytest.approx(length)
        if segment_crosses_box(start, goal, wall, R):
            assert length == pytest.approx(perimeter_geodesic(start, goal, wall, R))
        unrotated = np.array([0.0, 0.0, wall[2], wall[3], 0.0])
        assert length == pytest.approx(
            shortest_path_length(*to_wall_frame(np.stack([start, goal]), wall), unrotated, R)
        )


def test_orthographic_homography_maps_the_table_to_the_image():
    homography = plane_homography(np.array([0, 0, 1.0]), np.eye(3), 2.0, True, 64, 64, plane_z=0.06)
    pixels = apply_homography(homography, np.array([[-1.0, 1.0], [1.0, -1.0], [0.5, 0.25]]))
    assert np.allclose(pixels, [[0, 0], [64, 64], [48, 24]])


def test_perspective_homography_projects_the_optical_axis_to_the_centre():
    homography = plane_homography(np.array([0.2, -0.1, 2.0]), np.eye(3), 45.0, False, 64, 64, plane_z=0.0)
    assert np.allclose(apply_homography(homography, np.array([0.2, -0.1])), [32, 32])
    # A point at height 0, 2 units below the camera, offset by tan(22.5 deg) * 2 reaches the top edge.
    edge = apply_homography(homography, np.array([0.2, -0.1 + 2 * np.tan(np.deg2rad(22.5))]))
    assert np.allclose(edge, [32, 0])
