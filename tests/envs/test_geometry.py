"""Shortest path around the inflated wall and the camera homography (paper §4.2, App. 10)."""

import itertools
import math

import numpy as np
import pytest

from keyin.envs.geometry import (
    apply_homography,
    end_side,
    from_wall_frame,
    passing_side,
    plane_homography,
    segment_crosses_box,
    shortest_path,
    shortest_path_length,
    side_fractions,
    to_wall_frame,
    top_view_homography,
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


# Hand-made puck tracks past WALL (|x| <= 0.4 at y = 0), from below (y < 0) to above, and their sides.
ROUND_THE_RIGHT = np.array([[0.2, -0.5], [0.6, -0.2], [0.6, 0.2], [0.2, 0.5]])
TRACKS = {
    "right": ROUND_THE_RIGHT,
    "left": ROUND_THE_RIGHT * [-1, 1],
    "through": np.array([[0.0, -0.5], [0.1, -0.1], [0.1, 0.1], [0.0, 0.5]]),
    "none": np.array([[0.2, -0.5], [0.6, -0.2], [0.6, -0.01]]),  # never reaches the far side
}


@pytest.mark.parametrize("side", TRACKS)
def test_a_track_passes_the_wall_on_the_side_it_crosses_its_line(side):
    assert passing_side(TRACKS[side], WALL) == side


@pytest.mark.parametrize("angle", [0.35, -0.35])  # the data's walls lean up to 20 degrees either way
def test_the_side_turns_with_the_wall(angle):
    wall = np.array([0.1, -0.2, 0.4, 0.03, angle])
    for side, track in TRACKS.items():
        assert passing_side(from_wall_frame(track, wall), wall) == side


def test_right_is_the_wall_end_at_the_larger_x_whichever_way_the_wall_points():
    flipped = np.array([0.0, 0.0, 0.4, 0.03, np.pi])  # the same box, its axis pointing to -x
    assert passing_side(ROUND_THE_RIGHT, flipped) == "right"
    assert (end_side(1, WALL), end_side(-1, WALL), end_side(1, flipped)) == ("right", "left", "left")


def test_the_crossing_is_interpolated_over_frames_without_a_puck():
    # Between (0.2, -0.5) and (0.7, 0.3) the line y = 0 is crossed at x = 0.2 + 0.5 * 0.5 / 0.8 = 0.51 > 0.4.
    assert passing_side(np.array([[0.2, -0.5], [np.nan, np.nan], [0.7, 0.3]]), WALL) == "right"
    # ... and at x = 0.2 + 0.2 * 0.5 / 0.8 = 0.325 <= 0.4: through the wall.
    assert passing_side(np.array([[0.2, -0.5], [np.nan, np.nan], [0.4, 0.3]]), WALL) == "through"
    assert passing_side(np.array([[0.2, -0.5], [np.nan, np.nan]]), WALL) == "none"  # one point seen


def test_side_fractions_count_every_side():
    fractions = side_fractions(["left", "right", "right", "none"])
    assert fractions == {"count": 4, "left": 0.25, "right": 0.5, "through": 0.0, "none": 0.25}
    assert side_fractions([])["count"] == 0


def test_the_top_view_maps_the_table_to_the_image_and_back():
    homography = top_view_homography(64)
    points = np.array([[-1.0, 1.0], [1.0, -1.0], [0.5, 0.25]])
    assert np.allclose(apply_homography(homography, points), [[0, 0], [64, 64], [48, 24]])
    assert np.allclose(apply_homography(np.linalg.inv(homography), apply_homography(homography, points)), points)
