"""Plane geometry of the pushing scene: the wall, shortest paths around it, camera projection.

A wall is five numbers ``(cx, cy, half_length, half_thickness, angle)``: a box centred at
``(cx, cy)`` whose long axis makes ``angle`` radians with the world x axis. The position error of
the planning evaluation (paper §4.2) is the length of the shortest path of the puck's centre
from its position to the goal around the wall *inflated by the puck radius* (the set of centre
positions where the puck would overlap the wall): the Euclidean distance when the straight segment
is clear, otherwise Dijkstra on the visibility graph of {start, goal, the four inflated corners}.
The inflation keeps square corners: a path turning by theta at a corner is
``radius * (2 tan(theta / 2) - theta)`` longer than round the exact, rounded Minkowski sum (at most
``(2 - pi / 2) * radius`` ~ 0.026 for a 90-degree turn of the puck). docs/planning.md ("The servo") defines the
metric on the inflated box, and so does this module.

Pixel coordinates are continuous ``(u, v)`` = (column, row) with the image's top-left corner at
``(0, 0)``: pixel ``[row, col]`` covers ``[col, col + 1) x [row, row + 1)`` and its centre is
``(col + 0.5, row + 0.5)``. :func:`keyin.envs.segmentation.puck_centroid` uses the same convention.
"""

from __future__ import annotations

import heapq
import math

import numpy as np

# Tolerance (world units) for "touching is not crossing": a path may run along an inflated edge.
EDGE_TOL = 1e-9


def wall_axes(wall: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Centre (2,), unit long axis (2,) and unit normal (2,) of a wall (5,)."""
    angle = float(wall[4])
    axis = np.array([np.cos(angle), np.sin(angle)])
    normal = np.array([-np.sin(angle), np.cos(angle)])
    return np.asarray(wall[:2], dtype=np.float64), axis, normal


def to_wall_frame(points: np.ndarray, wall: np.ndarray) -> np.ndarray:
    """World points (..., 2) -> wall-frame coordinates (..., 2) = (along the wall, along its normal)."""
    centre, axis, normal = wall_axes(wall)
    rel = np.asarray(points, dtype=np.float64) - centre
    return np.stack([rel @ axis, rel @ normal], axis=-1)


def from_wall_frame(local: np.ndarray, wall: np.ndarray) -> np.ndarray:
    """Wall-frame coordinates (..., 2) -> world points (..., 2)."""
    centre, axis, normal = wall_axes(wall)
    local = np.asarray(local, dtype=np.float64)
    return centre + local[..., :1] * axis + local[..., 1:] * normal


def wall_corners(wall: np.ndarray, inflate: float = 0.0) -> np.ndarray:
    """The four corners (4, 2) of the wall box grown by ``inflate`` on every side, counter-clockwise."""
    half = np.array([wall[2] + inflate, wall[3] + inflate])
    signs = np.array([[1.0, 1.0], [-1.0, 1.0], [-1.0, -1.0], [1.0, -1.0]])
    return from_wall_frame(signs * half, wall)


def _crosses_local(p: tuple[float, float], q: tuple[float, float], half: tuple[float, float]) -> bool:
    """Segment p -> q against the open box ``|x| < half[0], |y| < half[1]`` (wall-frame floats)."""
    t_low, t_high = 0.0, 1.0
    for axis in range(2):
        delta = q[axis] - p[axis]
        if abs(delta) < 1e-15:
            if abs(p[axis]) >= half[axis]:
                return False
            continue
        t_a = (-half[axis] - p[axis]) / delta
        t_b = (half[axis] - p[axis]) / delta
        t_low = max(t_low, min(t_a, t_b))
        t_high = min(t_high, max(t_a, t_b))
    return t_high - t_low > 1e-12


def segment_crosses_box(start: np.ndarray, end: np.ndarray, wall: np.ndarray, inflate: float) -> bool:
    """Whether the segment start -> end (2,), (2,) passes through the open interior of the grown box.

    Segments that only touch the boundary (run along an edge, pass through a corner) do not cross.
    """
    half = (float(wall[2]) + inflate - EDGE_TOL, float(wall[3]) + inflate - EDGE_TOL)
    return _crosses_local(_local(start, wall), _local(end, wall), half)


def _local(point: np.ndarray, wall: np.ndarray) -> tuple[float, float]:
    """One world point -> wall-frame floats (fast path of :func:`to_wall_frame`)."""
    cos, sin = math.cos(wall[4]), math.sin(wall[4])
    dx, dy = float(point[0]) - float(wall[0]), float(point[1]) - float(wall[1])
    return (dx * cos + dy * sin, -dx * sin + dy * cos)


def _push_out_local(
    local: tuple[float, float], half: tuple[float, float]
) -> tuple[tuple[float, float], float]:
    """A wall-frame point inside the box moved to the nearest boundary point, and the move length."""
    depth = (half[0] - abs(local[0]), half[1] - abs(local[1]))
    if depth[0] <= 0.0 or depth[1] <= 0.0:
        return local, 0.0
    axis = 0 if depth[0] < depth[1] else 1
    moved = list(local)
    moved[axis] = math.copysign(half[axis], local[axis] if local[axis] != 0 else 1.0)
    return (moved[0], moved[1]), depth[axis]


def _visible(a: int, b: int, nodes: list[tuple[float, float]], test: tuple[float, float]) -> bool:
    """Visibility in the graph {0: start, 1: goal, 2..5: corners counter-clockwise}."""
    if a >= 2 and b >= 2:  # corners: neighbours see each other along an edge, opposite ones do not
        return (a - b) % 2 == 1
    return not _crosses_local(nodes[a], nodes[b], test)


def _shortest_local(
    start: tuple[float, float], goal: tuple[float, float], half: tuple[float, float]
) -> tuple[float, list[tuple[float, float]]]:
    """Dijkstra on {start, goal, 4 corners} around the open box ``|x| < half[0], |y| < half[1]``."""
    test = (half[0] - EDGE_TOL, half[1] - EDGE_TOL)
    if not _crosses_local(start, goal, test):
        return math.dist(start, goal), [start, goal]
    nodes = [start, goal] + [(sx * half[0], sy * half[1]) for sx, sy in ((1, 1), (-1, 1), (-1, -1), (1, -1))]
    best = [math.inf] * len(nodes)
    previous = [-1] * len(nodes)
    best[0] = 0.0
    queue = [(0.0, 0)]
    while queue:
        length, node = heapq.heappop(queue)
        if node == 1:
            break
        if length > best[node]:
            continue
        for other in range(1, len(nodes)):
            if other == node or not _visible(node, other, nodes, test):
                continue
            candidate = length + math.dist(nodes[node], nodes[other])
            if candidate < best[other]:
                best[other], previous[other] = candidate, node
                heapq.heappush(queue, (candidate, other))
    order = [1]
    while order[-1] != 0:
        order.append(previous[order[-1]])
    return best[1], [nodes[i] for i in reversed(order)]


def shortest_path(
    start: np.ndarray, goal: np.ndarray, wall: np.ndarray, inflate: float
) -> tuple[float, np.ndarray]:
    """Shortest path of a point from ``start`` to ``goal`` avoiding the wall grown by ``inflate``.

    A start or goal inside the grown box (a puck pressed into the wall) is first moved to the box's
    boundary and the move is added to the length. The work happens in the wall frame, where the
    box is axis-aligned (lengths do not change under the rotation).

    Args:
        start, goal: (2,) world positions.
        wall: (5,) ``(cx, cy, half_length, half_thickness, angle)``.
        inflate: grow the box by this much on every side (the puck radius).
    Returns:
        length: the path length (world units).
        path: (K, 2) world vertices of the path after the push-out, start and goal included.
    """
    half = (float(wall[2]) + inflate, float(wall[3]) + inflate)
    start_local, extra_start = _push_out_local(_local(start, wall), half)
    goal_local, extra_goal = _push_out_local(_local(goal, wall), half)
    length, nodes = _shortest_local(start_local, goal_local, half)
    return length + extra_start + extra_goal, from_wall_frame(np.array(nodes), wall)


def shortest_path_length(start: np.ndarray, goal: np.ndarray, wall: np.ndarray, inflate: float) -> float:
    """Length of :func:`shortest_path` (the paper's position error when ``start`` is the final puck)."""
    half = (float(wall[2]) + inflate, float(wall[3]) + inflate)
    start_local, extra_start = _push_out_local(_local(start, wall), half)
    goal_local, extra_goal = _push_out_local(_local(goal, wall), half)
    return _shortest_local(start_local, goal_local, half)[0] + extra_start + extra_goal


def plane_homography(
    cam_pos: np.ndarray,
    cam_mat: np.ndarray,
    fovy: float,
    orthographic: bool,
    width: int,
    height: int,
    plane_z: float,
) -> np.ndarray:
    """The 3x3 map from world points ``(x, y, plane_z)`` to pixel coordinates of a MuJoCo camera.

    MuJoCo cameras look along their local -z axis with +y up in the image. A perspective camera's
    ``fovy`` is the vertical field of view in degrees; an orthographic camera's is the height of the
    view in world units.

    Args:
        cam_pos: (3,) camera position (``data.cam_xpos``).
        cam_mat: (3, 3) camera-to-world rotation (``data.cam_xmat`` reshaped); columns = camera axes.
        plane_z: height of the world plane the points lie in.
    Returns:
        (3, 3) H with ``[u w, v w, w] = H @ [x, y, 1]``; use :func:`apply_homography`.
    """
    rotation = np.asarray(cam_mat, dtype=np.float64).reshape(3, 3).T  # world -> camera
    # Camera coordinates of (x, y, plane_z) are affine in (x, y): columns for x, y and the constant.
    affine = np.column_stack(
        [rotation[:, 0], rotation[:, 1], rotation @ (np.array([0.0, 0.0, plane_z]) - cam_pos)]
    )
    if orthographic:
        scale = height / fovy  # pixels per world unit
        to_pixels = np.array(
            [[scale, 0.0, 0.0, width / 2.0], [0.0, -scale, 0.0, height / 2.0], [0.0, 0.0, 0.0, 1.0]]
        )
    else:
        focal = (height / 2.0) / np.tan(np.deg2rad(fovy) / 2.0)
        # Perspective divide by depth = -z_camera.
        to_pixels = np.array(
            [[focal, 0.0, -width / 2.0, 0.0], [0.0, -focal, -height / 2.0, 0.0], [0.0, 0.0, -1.0, 0.0]]
        )
    homogeneous = np.vstack([affine, [0.0, 0.0, 1.0]])  # (x, y, 1) -> (camera xyz, 1)
    return to_pixels @ homogeneous


def apply_homography(homography: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Pixel coordinates (..., 2) = (column, row) of world points (..., 2) in the homography's plane."""
    points = np.asarray(points, dtype=np.float64)
    mapped = points @ homography[:, :2].T + homography[:, 2]
    return mapped[..., :2] / mapped[..., 2:]


VIEW_HALF = 1.0
"""The top camera of :mod:`keyin.envs.pushing` films ``[-VIEW_HALF, VIEW_HALF]²`` straight down,
orthographic (its ``fovy`` is ``2 * VIEW_HALF``)."""


def top_view_homography(image_size: int) -> np.ndarray:
    """(3, 3) world (x, y) -> pixel (column, row) of the top camera at ``image_size`` pixels, without
    MuJoCo: :meth:`keyin.envs.pushing.PushingPhysics.homography` (tests/envs/test_pushing.py)."""
    return plane_homography(
        np.array([0.0, 0.0, 1.0]), np.eye(3), 2 * VIEW_HALF, True, image_size, image_size, plane_z=0.0
    )


PASSING_SIDES = ("left", "right", "through", "none")
"""How a puck track goes past the wall (:func:`passing_side`)."""


def end_side(end: float, wall: np.ndarray) -> str:
    """"right" or "left": the wall end at wall-frame ``sign(end)`` (the demonstrator's detour
    ``side``) is the one at the larger or the smaller world x, i.e. on the right or the left of the
    top camera's picture (pixel columns grow with x)."""
    return "right" if np.sign(end) * math.cos(float(wall[4])) > 0 else "left"


def passing_side(track: np.ndarray, wall: np.ndarray) -> str:
    """Which way a puck track goes past the wall: one of :data:`PASSING_SIDES`.

    In the wall frame (:func:`to_wall_frame`: ``a`` along the wall, ``n`` along its normal) the
    track starts on the side ``sign(n)`` of its first point; it *crosses* at the first point with
    ``n`` of the other sign, at ``a*``, the along-coordinate where the segment from the point
    before reaches ``n = 0`` (linear interpolation). A crossing with ``|a*| > half_length`` passes
    round the end ``sign(a*)``: "right" or "left" as :func:`end_side` names it; one with
    ``|a*| <= half_length`` went "through" the wall (impossible in the scene, possible for a
    model's prediction); a track that never reaches the other side, or has fewer than two points,
    is "none".

    Args:
        track: (T, 2) world positions in order; rows with a NaN (the puck not seen) are skipped.
        wall: (5,) ``(cx, cy, half_length, half_thickness, angle)``.
    """
    points = track[~np.isnan(track).any(axis=-1)]
    if len(points) < 2:
        return "none"
    local = to_wall_frame(points, wall)  # (T', 2)
    far = np.flatnonzero(local[:, 1] * local[0, 1] < 0)
    if not len(far):
        return "none"
    (a0, n0), (a1, n1) = local[far[0] - 1], local[far[0]]
    crossing = a0 + (a1 - a0) * n0 / (n0 - n1)
    return "through" if abs(crossing) <= wall[2] else end_side(crossing, wall)


def side_fractions(sides: list[str]) -> dict[str, float | int]:
    """``count`` and, per entry of :data:`PASSING_SIDES`, the fraction of ``sides`` that are it."""
    count = len(sides)
    return {"count": count, **{side: sides.count(side) / count if count else 0.0 for side in PASSING_SIDES}}
