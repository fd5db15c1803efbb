"""Analytic top-camera renderer of the pushing scene: MuJoCo's pixels in numpy, without OpenGL.

The scene (:func:`keyin.envs.pushing.make_model`) is flat-coloured, lit by an ambient-only
headlight and filmed by an orthographic camera looking straight down at ``[-1, 1]²``, without
shadows or multisampling, so every pixel shows the colour of the highest surface at its centre.
This module reproduces what MuJoCo draws through Mesa's llvmpipe (the software renderer behind
EGL here), conventions included; ``tests/envs/test_render.py`` compares the two:

* **Tessellation.** A box's top face is a 4 x 4 grid of quads (``numquads``), a sphere has 28
  slices and 16 stacks (``numslices``, ``numstacks``; MuJoCo's defaults): seen from the top a
  sphere is the 28-gon of its equator (a vertex at azimuth 0), and its height is piecewise linear
  in the distance along each slice's bisector.
* **Vertices** are computed in float32 (geom position plus the model-view offset, then the
  viewport) and snapped to 1/256 pixel, half to even.
* **Coverage.** A pixel is covered when its centre is inside; a centre exactly on an edge or a
  vertex counts as if nudged right, then up (llvmpipe's fill rule, in window coordinates).
* **Depth.** The highest surface wins; on equal heights the geom drawn later (model order: table,
  borders, wall, pusher, puck) wins.
* **Colour.** The lit colour is the geom's RGB; 8 bits are ``rint(float32(c) * 255)``, half to
  even (0.3 -> 76, 0.1 -> 26).

Window coordinates have y up, so window row ``k`` is image row ``size - 1 - k``; image pixel
``(col, row)`` has its centre at world ``(-1 + (col + 0.5) / s, 1 - (row + 0.5) / s)``, ``s =
size / 2`` pixels per unit. Heights are the exact faceted ones, not MuJoCo's float32 depth buffer
(one step ~1e-5 units at the tops of the boxes): where the puck's surface comes within a step of a
box top (only when it overlaps the wall or the border) the two renderers can disagree on a pixel.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from keyin.envs.pushing import BOX_HALF_HEIGHT, COLOURS, SceneParams, border_boxes

SUBPIXEL = 256  # llvmpipe snaps vertices to 1/256 pixel
BOX_QUADS = 4  # MuJoCo's ``visual/quality/numquads``: quads per box face side
SPHERE_SLICES = 28  # ``numslices``
SPHERE_STACKS = 16  # ``numstacks``
BOX_TOP = 2 * BOX_HALF_HEIGHT  # height of the border and wall tops
REACH_SLACK = 0.01  # pixels: snapped equator vertices stay within 0.003 px of the exact circle


def rgb8(colour: tuple[float, float, float]) -> np.ndarray:
    """(3,) uint8 that llvmpipe writes for a flat RGB colour in [0, 1]."""
    return np.rint(np.asarray(colour, np.float32) * np.float32(255)).astype(np.uint8)


def to_window(position: np.ndarray, offset: np.ndarray, size: int) -> np.ndarray:
    """Snapped window coordinates (..., 2) int64, in 1/256 pixel, of a geom's vertices.

    Computed in float32 as MuJoCo and llvmpipe do: the vertex is the geom position (float32) plus
    its model-view offset, mapped by the viewport to ``(x + 1) * size / 2``, less the half-pixel
    centre offset, then rounded to the 1/256 grid (half to even). The origin is the centre of
    window pixel (0, 0), so pixel ``(i, k)`` sits at ``(i * SUBPIXEL, k * SUBPIXEL)``.

    Args:
        position: (..., 2) world position of the geom's centre.
        offset: (..., 2) float32 vertex offsets from it (``box_top_offsets``, ``equator_offsets``).
    """
    world = np.asarray(offset, np.float32) + np.asarray(position, np.float32)
    half = np.float32(size / 2)
    window = world * half + half
    return np.rint((window - np.float32(0.5)) * np.float32(SUBPIXEL)).astype(np.int64)


def _left_of(direction: np.ndarray, offset: np.ndarray) -> np.ndarray:
    """Whether ``offset`` (..., 2) lies left of a line with ``direction`` (..., 2), both int64.

    A point exactly on the line is nudged right, then up (``(1, +0)``): that is llvmpipe's fill
    rule (an edge keeps its ties when its inward normal points right, or straight up), applied
    the same way to edges, shared vertices and the interior lines of :func:`polygon_coverage`.
    """
    cross = direction[..., 0] * offset[..., 1] - direction[..., 1] * offset[..., 0]
    nudge = (direction[..., 1] < 0) | ((direction[..., 1] == 0) & (direction[..., 0] > 0))
    return (cross > 0) | ((cross == 0) & nudge)


def polygon_coverage(centre: np.ndarray, ring: np.ndarray, pixels: np.ndarray) -> np.ndarray:
    """Which pixels the rasteriser fills for a polygon star-shaped around ``centre``.

    The polygon is the fan of triangles ``(centre, ring[j], ring[j + 1])``: a pixel is covered when
    its nudged centre lies in some fan triangle, which is what any triangulation of the polygon
    gives (MuJoCo's quads included).

    Args:
        centre: (..., 2) int64 window point inside the polygon.
        ring: (..., M, 2) int64 window vertices, counter-clockwise.
        pixels: (..., P, 2) int64 window pixel centres.

    Returns:
        (..., P) bool.
    """
    edge = np.roll(ring, -1, axis=-2) - ring  # (..., M, 2)
    inside = _left_of(edge[..., None, :, :], pixels[..., :, None, :] - ring[..., None, :, :])  # (..., P, M)
    spoke = ring - centre[..., None, :]
    after = _left_of(spoke[..., None, :, :], (pixels - centre[..., None, :])[..., :, None, :])
    in_fan = after & ~np.roll(after, -1, axis=-1)  # between spokes j and j + 1
    return np.any(inside & in_fan, axis=-1)


def box_top_offsets(half: np.ndarray, angle: float) -> np.ndarray:
    """(4 * BOX_QUADS, 2) float32 offsets of the vertices round a box's top face, counter-clockwise.

    MuJoCo scales the unit box's grid points ``u`` (multiples of 1 / 2, exact) by the float32
    model-view columns ``rotation * half``: the offset is one float32 rounding of their sum.

    Args:
        half: (2,) half sizes along the box axes; angle: of the box's x axis to the world's.
    """
    steps = np.linspace(-1.0, 1.0, BOX_QUADS + 1)[:-1]
    ones = np.ones(BOX_QUADS)
    unit = np.concatenate([
        np.stack([steps, -ones], -1), np.stack([ones, steps], -1),
        np.stack([-steps, ones], -1), np.stack([-ones, -steps], -1),
    ])
    rotation = np.array([[math.cos(angle), -math.sin(angle)], [math.sin(angle), math.cos(angle)]], np.float32)
    columns = (rotation * np.asarray(half, np.float64).astype(np.float32)).astype(np.float64)
    return (unit @ columns.T).astype(np.float32)


@functools.lru_cache(maxsize=8)
def equator_offsets(radius: float) -> np.ndarray:
    """(SPHERE_SLICES, 2) float32 offsets of a sphere's equator vertices, counter-clockwise.

    The azimuths are float32 like MuJoCo's ``2 pi j / numslices``, their cosines and sines float32.
    """
    azimuth = (2 * np.pi * np.arange(SPHERE_SLICES) / SPHERE_SLICES).astype(np.float32).astype(np.float64)
    offsets = np.float32(radius) * np.stack([np.cos(azimuth), np.sin(azimuth)], -1).astype(np.float32)
    offsets.flags.writeable = False  # cached
    return offsets


def sphere_height(offset: np.ndarray, radius: float) -> np.ndarray:
    """Height (...) of the tessellated sphere's upper surface above its centre at ``offset`` (..., 2).

    Within a slice the facets between two stacks are planar and horizontal along the slice, so
    the height depends only on the distance ``s`` along the slice's bisector (the largest
    projection on the 28 bisectors); it is 0 beyond the equator polygon.
    """
    bisectors = 2 * np.pi * (np.arange(SPHERE_SLICES) + 0.5) / SPHERE_SLICES
    s = np.max(offset[..., :1] * np.cos(bisectors) + offset[..., 1:] * np.sin(bisectors), axis=-1)
    elevation = 0.5 * np.pi * np.arange(SPHERE_STACKS // 2, -1, -1) / (SPHERE_STACKS // 2)  # pole first
    ring_s = radius * np.cos(elevation) * math.cos(np.pi / SPHERE_SLICES)
    return np.interp(s, ring_s, radius * np.sin(elevation), right=0.0)


def box_mask(centre: np.ndarray, half: np.ndarray, angle: float, size: int) -> np.ndarray:
    """(size, size) bool, window rows: the pixels a box's top face covers (tested in its bounds).

    Args:
        centre: (2,) world centre; half: (2,) half sizes along the box axes; angle: of its x axis.
    """
    ring = to_window(centre, box_top_offsets(half, angle), size)
    low = np.clip(-(-ring.min(axis=0) // SUBPIXEL), 0, size)  # first and past-the-last pixel (i, k)
    high = np.clip(ring.max(axis=0) // SUBPIXEL + 1, low, size)
    cols, rows = np.meshgrid(np.arange(low[0], high[0]), np.arange(low[1], high[1]))
    pixels = np.stack([cols, rows], -1).reshape(-1, 2) * SUBPIXEL
    mask = np.zeros((size, size), bool)
    covered = polygon_coverage(to_window(centre, np.zeros(2), size), ring, pixels)
    mask[low[1]:high[1], low[0]:high[0]] = covered.reshape(cols.shape)
    return mask


@functools.lru_cache(maxsize=4)
def _table_and_border(scene: SceneParams) -> tuple[np.ndarray, np.ndarray]:
    """(size, size, 3) uint8 colours and (size, size) heights of the table and the border."""
    size = scene.image_size
    colour = np.broadcast_to(rgb8(COLOURS["table"]), (size, size, 3)).copy()
    height = np.zeros((size, size))
    for cx, cy, hx, hy in border_boxes(scene):
        covered = box_mask(np.array([cx, cy]), np.array([hx, hy]), 0.0, size)
        colour[covered], height[covered] = rgb8(COLOURS["border"]), BOX_TOP
    colour.flags.writeable = height.flags.writeable = False  # cached
    return colour, height


def background(scene: SceneParams, wall: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(size, size, 3) uint8 colours and (size, size) surface heights of table, border and wall.

    Rows are window rows (y up). ``wall`` is (5,) ``(cx, cy, half_length, half_thickness, angle)``.
    """
    colour, height = (a.copy() for a in _table_and_border(scene))
    covered = box_mask(wall[:2], wall[2:4], float(wall[4]), scene.image_size)
    colour[covered], height[covered] = rgb8(COLOURS["wall"]), BOX_TOP
    return colour, height


def _span(radius: float, size: int) -> int:
    """Side of the pixel window that holds every pixel centre a sphere can cover."""
    return math.floor(2 * (radius * size / 2 + REACH_SLACK)) + 1


def _draw_spheres(
    colour: np.ndarray, height: np.ndarray, centres: np.ndarray, radius: float, z: float,
    rgb: np.ndarray, scene: SceneParams, margin: int,
) -> None:
    """Draw one sphere per frame into the padded canvases, in place (depth test ``>=``).

    Args:
        colour: (K, C, C, 3) uint8 and height: (K, C, C) float canvases padded by ``margin``.
        centres: (K, 2) world sphere centres; z: height of the centres.
    """
    size, per_unit = scene.image_size, scene.image_size / 2
    span = _span(radius, size)
    reach = radius * per_unit + REACH_SLACK
    corner = np.ceil((centres + 1.0) * per_unit - 0.5 - reach).astype(np.int64)
    corner = np.clip(corner, -margin, size + margin - span)  # (K, 2) window (i, k) of the first pixel
    steps = np.arange(span)
    cols = corner[:, None, 0] + steps  # (K, span)
    rows = corner[:, None, 1] + steps
    grid = np.stack(np.broadcast_arrays(cols[:, None, :], rows[:, :, None]), -1)  # (K, span, span, 2)
    ring = to_window(centres[:, None, :], equator_offsets(radius), size)
    covered = polygon_coverage(
        to_window(centres, np.zeros(2), size), ring, grid.reshape(len(centres), -1, 2) * SUBPIXEL
    ).reshape(grid.shape[:-1])
    world = (grid + 0.5) / per_unit - 1.0
    top = z + sphere_height(world - centres[:, None, None, :], radius)
    frame = np.arange(len(centres))[:, None, None]
    at = (frame, rows[:, :, None] + margin, cols[:, None, :] + margin)
    win = covered & (top >= height[at])
    colour[at] = np.where(win[..., None], rgb, colour[at])
    height[at] = np.where(win, top, height[at])


def render_top(scene: SceneParams, wall: np.ndarray, puck: np.ndarray, pusher: np.ndarray) -> np.ndarray:
    """Top-camera images of one layout, as ``PushingPhysics.render_top`` draws them.

    Args:
        scene: the scene constants (radii, arena, image size).
        wall: (5,) ``(cx, cy, half_length, half_thickness, angle)``.
        puck, pusher: (K, 2) world positions of their centres.

    Returns:
        (K, size, size, 3) uint8, row 0 at the top (y = 1).
    """
    puck, pusher = np.asarray(puck, np.float64).reshape(-1, 2), np.asarray(pusher, np.float64).reshape(-1, 2)
    size = scene.image_size
    margin = _span(max(scene.puck_radius, scene.pusher_radius), size)
    colour, height = background(scene, np.asarray(wall, np.float64))
    pad = ((margin, margin), (margin, margin))
    colour = np.repeat(np.pad(colour, (*pad, (0, 0)))[None], len(puck), axis=0)
    height = np.repeat(np.pad(height, pad)[None], len(puck), axis=0)
    z = scene.puck_radius  # both centres are at the puck's radius above the table (make_model)
    for centres, radius, name in ((pusher, scene.pusher_radius, "pusher"), (puck, scene.puck_radius, "puck")):
        _draw_spheres(colour, height, centres, radius, z, rgb8(COLOURS[name]), scene, margin)
    return np.ascontiguousarray(colour[:, margin: margin + size, margin: margin + size][:, ::-1])
