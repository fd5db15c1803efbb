"""The analytic renderer against MuJoCo's own top camera (llvmpipe through EGL on this machine).

Measured with ``random_scene`` (4 seeds x 5,000 scenes): 7 images differ, by one pixel each, all
depth ties (the puck's surface 1.5e-6 to 2.1e-5 units below the wall, border or pusher there,
within about two steps of MuJoCo's float32 depth buffer, and MuJoCo draws the puck); 300 generated
demos (17,916 raw frames) and the crafted fill-rule cases below are identical
(docs/pushing.md, "Analytic rendering").
"""

import numpy as np
import pytest

from keyin.data.pushing import PushingGenerator
from keyin.envs.geometry import from_wall_frame
from keyin.envs.pushing import COLOURS, pushing
from keyin.envs.render import BOX_QUADS, BOX_TOP, SPHERE_SLICES, SPHERE_STACKS, render_top, rgb8, sphere_height

DEPTH_TIE = 3e-5  # units: about two steps of MuJoCo's float32 depth buffer at the box tops


@pytest.fixture(scope="module")
def env():
    return pushing(random=0, pixels=False)


def mujoco_image(env, wall: np.ndarray, puck: np.ndarray, pusher: np.ndarray) -> np.ndarray:
    physics = env.physics
    physics.set_wall(wall)
    with physics.reset_context():
        physics.set_positions(puck, pusher)
    return physics.render_top()


def analytic_image(env, wall: np.ndarray, puck: np.ndarray, pusher: np.ndarray) -> np.ndarray:
    return render_top(env.task.scene, wall, puck[None], pusher[None])[0]


def random_scene(env, rng: np.random.Generator, kind: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A layout's wall (any angle for kind 0) and puck / pusher positions that stress the renderer:
    0 anywhere (on the border and past it too), 1 the puck touching or overlapping the wall and the
    pusher at it, 2 the pusher overlapping the puck, 3 both at the border."""
    wall = env.task.sampler.sample(rng).wall
    if kind == 0:
        wall[4] = rng.uniform(-np.pi, np.pi)
        return wall, rng.uniform(-1.05, 1.05, 2), rng.uniform(-1.05, 1.05, 2)
    if kind == 1:
        puck = from_wall_frame(np.array([rng.uniform(-0.5, 0.5), rng.choice([-1, 1]) * rng.uniform(0, 0.1)]), wall)
        return wall, puck, puck + rng.normal(size=2) * 0.07
    if kind == 2:
        puck, direction = rng.uniform(-0.9, 0.9, 2), rng.normal(size=2)
        return wall, puck, puck + direction / np.linalg.norm(direction) * rng.uniform(0.0, 0.1)
    puck, pusher, axis = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 2), rng.integers(2)
    puck[axis] = rng.choice([-1, 1]) * rng.uniform(0.85, 1.02)
    pusher[1 - axis] = rng.choice([-1, 1]) * rng.uniform(0.85, 1.02)
    return wall, puck, pusher


def test_scene_constants_are_mujocos(env):
    model = env.physics.model
    quality = model.vis.quality
    assert (quality.numslices, quality.numstacks, quality.numquads) == (SPHERE_SLICES, SPHERE_STACKS, BOX_QUADS)
    for name, colour in COLOURS.items():
        geom = model.name2id("border0" if name == "border" else name, "geom")
        assert np.allclose(model.geom_rgba[geom, :3], colour)
    assert [tuple(rgb8(COLOURS[name])) for name in ("border", "pusher")] == [(76, 76, 76), (242, 140, 26)]


def depth_tie(env, image: np.ndarray, row: int, col: int, puck: np.ndarray, pusher: np.ndarray) -> bool:
    """Whether MuJoCo shows the puck at a pixel where the analytic puck surface is at most
    DEPTH_TIE below the box tops or the pusher's surface (float32 depth-buffer precision)."""
    scene = env.task.scene
    centre = np.array([-1 + (col + 0.5) / 32, 1 - (row + 0.5) / 32])
    puck_top = sphere_height(centre - puck, scene.puck_radius)
    others = (BOX_TOP - scene.puck_radius, sphere_height(centre - pusher, scene.pusher_radius))
    close = any(0 <= other - puck_top <= DEPTH_TIE for other in others)
    return close and tuple(image[row, col]) == tuple(rgb8(COLOURS["puck"]))


def test_random_scenes_match_mujoco(env):
    rng = np.random.default_rng(0)
    differing = []
    for index in range(400):
        wall, puck, pusher = random_scene(env, rng, index % 4)
        reference = mujoco_image(env, wall, puck, pusher)
        for row, col in np.argwhere(np.any(analytic_image(env, wall, puck, pusher) != reference, axis=-1)):
            differing.append(index)
            assert depth_tie(env, reference, row, col, puck, pusher), (index, row, col)
    # Measured: one pixel (image 347: the puck sunk into the border, 9e-6 below its top).
    assert len(differing) <= 2 and len(set(differing)) == len(differing), differing


@pytest.mark.parametrize("angle", [0.0, np.pi / 2, np.arctan2(1, 4), -np.arctan2(1, 4), np.pi + np.arctan2(1, 4)])
@pytest.mark.parametrize("shift", [-2, -1, 0, 1, 2])
def test_edges_and_corners_through_pixel_centres(env, angle, shift):
    # Walls whose edges and corners run exactly through pixel centres (to 1/1024 pixel): the fill
    # rule, snapping and half-way rounding decide every pixel along them.
    half_length, half_thickness = 17**0.5 / 16, 0.03  # a long edge spans 4 x (4, 1) pixels at atan(1/4)
    corner = (np.array([20.5, 30.5]) + shift / 1024) / 32 - 1  # window pixel centre -> world
    axis = np.array([np.cos(angle), np.sin(angle)])
    normal = np.array([-np.sin(angle), np.cos(angle)])
    for side in (1, -1):
        centre = corner + half_length * axis - side * half_thickness * normal
        wall = np.array([*centre, half_length, half_thickness, angle])
        puck, pusher = np.array([0.8, -0.8]), np.array([-0.8, -0.8])
        assert np.array_equal(analytic_image(env, wall, puck, pusher), mujoco_image(env, wall, puck, pusher))


def test_sphere_centres_on_the_pixel_lattice(env):
    wall = np.array([0.0, 0.5, 0.4, 0.03, 0.0])
    for offset in ([0.5, 0.5], [0.0, 0.0], [0.5, 0.0], [0.25, 0.75]):
        pixel = np.array([30.0, 20.0]) + offset  # window coordinates of the centres
        puck = pixel / 32 - 1
        for pusher in (puck + [0.0, 0.09], puck + [0.1, 0.0]):
            assert np.array_equal(analytic_image(env, wall, puck, pusher), mujoco_image(env, wall, puck, pusher))


def test_generator_renderers_agree():
    analytic, mujoco = PushingGenerator(), PushingGenerator(renderer="mujoco")
    for index in range(2):
        a, b = analytic.generate(index, seed=3)[0], mujoco.generate(index, seed=3)[0]
        assert a.keys() == b.keys()
        for name in a:
            assert np.array_equal(a[name], b[name]), name
    with pytest.raises(ValueError, match="renderer"):
        PushingGenerator(renderer="opengl")


def test_batch_equals_single_frames(env):
    rng = np.random.default_rng(5)
    wall = env.task.sampler.sample(rng).wall
    puck, pusher = rng.uniform(-1, 1, (6, 2)), rng.uniform(-1, 1, (6, 2))
    batch = render_top(env.task.scene, wall, puck, pusher)
    assert batch.shape == (6, 64, 64, 3) and batch.dtype == np.uint8
    for k in range(6):
        assert np.array_equal(batch[k], analytic_image(env, wall, puck[k], pusher[k]))
