"""The pushing task on dm_control (paper App. 7, docs/pushing.md), after ``suite/point_mass.py``.

A top-down table ``[-1, 1]²`` with a low border, one wall with random length, angle and offset, a
purple puck and an orange pusher (the arm's end effector), each a sphere on two planar slide
joints. Planar slide joints get no table friction, so the puck's joints carry damping and dry
friction (``frictionloss``): it stops within about 0.02 once the pusher lets go (quasi-static
pushing). The pusher is driven by two velocity servos: an action ``a`` in ``[-1, 1]²`` commands the
velocity ``v_max * a``. Actions outside ``[-1, 1]`` are **clipped** per component (the planner's
CEM clips its samples to ``a_max = 1`` the same way, paper App. 10); non-finite actions raise
``ValueError``. One environment step is ``control_timestep = 0.1`` s (10 physics steps of 10 ms);
the dataset keeps every second frame.

Lighting is one ambient-only headlight, so every surface renders as its flat ``rgba`` colour (the
puck is exactly ``PUCK_RGB``); shadows and multisampling are off (with a shadow-casting light and
4x MSAA a software-rendered frame took ~450 ms here instead of 2-6 ms). The camera is orthographic, so world -> pixel is affine
(:meth:`PushingPhysics.homography`); :mod:`keyin.envs.render` draws the same images in numpy.
"""

from __future__ import annotations

import collections
from dataclasses import dataclass

import numpy as np
from dm_control import mujoco
from dm_control.mujoco.engine import Camera
from dm_control.rl import control
from dm_control.suite import base
from dm_control.utils import containers

from keyin.envs.geometry import apply_homography, plane_homography, shortest_path_length
from keyin.envs.layout import Layout, LayoutSampler
from keyin.envs.segmentation import PUCK_RGB, PUSHER_RGB

SUITE = containers.TaggedTasks()
DEFAULT_TIME_LIMIT = 12.0  # s: 120 control steps = 60 saved frames = the servo's T_max (paper Table 3)
CAMERA = "top"
REWARD_MARGIN = 1.5  # path length beyond the goal tolerance at which the reward reaches 0
# Flat RGB colours of the geoms (ambient-only lighting renders them unchanged).
COLOURS = {"table": (0.85, 0.85, 0.85), "border": (0.3, 0.3, 0.3), "wall": (0.15, 0.35, 0.85),
           "pusher": PUSHER_RGB, "puck": PUCK_RGB}
BOX_HALF_HEIGHT = 0.05  # border and wall boxes stand on the table: tops at 0.1


@dataclass(frozen=True)
class SceneParams:
    """Physical and rendering constants of the scene (plain numbers; see docs/pushing.md)."""

    puck_radius: float = 0.06
    pusher_radius: float = 0.04
    puck_mass: float = 0.2
    puck_damping: float = 5.0  # N s / unit: the puck coasts ~mass/damping = 0.04 s
    puck_frictionloss: float = 0.1  # N: dry friction that makes it stop
    pusher_mass: float = 1.0
    pusher_kv: float = 100.0  # velocity-servo gain, N s / unit
    v_max: float = 1.0  # units / s at |action| = 1
    timestep: float = 0.01  # 10 physics steps per control step
    contact_timeconst: float = 0.02  # MuJoCo solref; must be >= 2 * timestep
    control_timestep: float = 0.1
    image_size: int = 64
    arena_half: float = 0.95  # free table inside the border
    goal_tolerance: float = 0.05


def border_boxes(scene: SceneParams) -> list[tuple[float, float, float, float]]:
    """The four border boxes ``(cx, cy, half_x, half_y)`` round the free table ``[-arena_half,
    arena_half]²``."""
    border = 1.0 - scene.arena_half
    sides = [(s * (1 - border / 2), 0.0, border / 2, 1.0) for s in (-1, 1)]
    return sides + [(0.0, s * (1 - border / 2), 1.0, border / 2) for s in (-1, 1)]


def make_model(scene: SceneParams) -> str:
    """The MJCF of the scene; the wall is resized and placed per episode by ``set_wall``."""
    z = scene.puck_radius  # puck and pusher centres share one height: contact normals stay planar
    h = BOX_HALF_HEIGHT
    colours = {name: " ".join(str(c) for c in rgb) + " 1" for name, rgb in COLOURS.items()}
    borders = "\n".join(
        f'    <geom name="border{i}" type="box" pos="{cx} {cy} {h}" size="{hx} {hy} {h}" '
        f'rgba="{colours["border"]}"/>'
        for i, (cx, cy, hx, hy) in enumerate(border_boxes(scene))
    )
    servo = (f'gaintype="fixed" gainprm="{scene.pusher_kv * scene.v_max}" biastype="affine" '
             f'biasprm="0 0 {-scene.pusher_kv}" ctrlrange="-1 1" ctrllimited="true"')
    puck_joint = f'damping="{scene.puck_damping}" frictionloss="{scene.puck_frictionloss}"'
    return f"""
<mujoco model="keyin_pushing">
  <compiler angle="radian"/>
  <option timestep="{scene.timestep}" integrator="implicitfast"/>
  <visual>
    <global offwidth="{scene.image_size}" offheight="{scene.image_size}"/>
    <quality shadowsize="0" offsamples="0"/>
    <headlight ambient="1 1 1" diffuse="0 0 0" specular="0 0 0"/>
  </visual>
  <default>
    <geom condim="1" solref="{scene.contact_timeconst} 1" contype="1" conaffinity="1"/>
    <joint type="slide" limited="false"/>
  </default>
  <worldbody>
    <geom name="table" type="plane" size="1 1 0.1" rgba="{colours["table"]}" contype="0" conaffinity="0"/>
{borders}
    <camera name="{CAMERA}" pos="0 0 1" projection="orthographic" fovy="2"/>
    <body name="wall" pos="0 0.3 {h}">
      <geom name="wall" type="box" size="0.4 0.03 {h}" rgba="{colours["wall"]}"/>
    </body>
    <body name="pusher" pos="0 0 {z}">
      <joint name="pusher_x" axis="1 0 0"/>
      <joint name="pusher_y" axis="0 1 0"/>
      <geom name="pusher" type="sphere" size="{scene.pusher_radius}" mass="{scene.pusher_mass}"
            rgba="{colours["pusher"]}"/>
    </body>
    <body name="puck" pos="0 0 {z}">
      <joint name="puck_x" axis="1 0 0" {puck_joint}/>
      <joint name="puck_y" axis="0 1 0" {puck_joint}/>
      <geom name="puck" type="sphere" size="{scene.puck_radius}" mass="{scene.puck_mass}"
            rgba="{colours["puck"]}"/>
    </body>
  </worldbody>
  <actuator>
    <general name="pusher_vx" joint="pusher_x" {servo}/>
    <general name="pusher_vy" joint="pusher_y" {servo}/>
  </actuator>
</mujoco>
"""


class PushingPhysics(mujoco.Physics):
    """Physics with named accessors for the pushing scene; positions are (x, y) world units."""

    # qpos / qvel layout, fixed by the MJCF order (checked in tests/envs/test_pushing.py).
    PUSHER = slice(0, 2)
    PUCK = slice(2, 4)

    def after_reset(self) -> None:
        """``mj_forward`` with actuation enabled, after ``reset_context()`` and ``copy()``.

        dm_control's ``after_reset`` disables actuation, which leaves ``actuator_velocity`` at 0;
        the next ``step`` starts with ``mj_step2`` (it trusts that ``mj_step1`` ran), so its first
        physics step lost the velocity servo's damping ``-kv v`` (0.005 units off after one
        environment step from a state with the pusher moving). The forces computed here from the
        stale controls are never used: every step sets the controls first (``Pushing.before_step``).
        """
        self.forward()

    def puck_position(self) -> np.ndarray:
        """(2,) copy of the puck centre."""
        return self.data.qpos[self.PUCK].copy()

    def pusher_position(self) -> np.ndarray:
        """(2,) copy of the pusher centre."""
        return self.data.qpos[self.PUSHER].copy()

    def puck_velocity(self) -> np.ndarray:
        return self.data.qvel[self.PUCK].copy()

    def pusher_velocity(self) -> np.ndarray:
        return self.data.qvel[self.PUSHER].copy()

    def set_positions(self, puck: np.ndarray, pusher: np.ndarray) -> None:
        """Place puck and pusher at rest (call ``forward`` or use ``reset_context`` afterwards)."""
        self.data.qpos[self.PUCK] = puck
        self.data.qpos[self.PUSHER] = pusher
        self.data.qvel[:] = 0.0

    def wall(self) -> np.ndarray:
        """(5,) ``(cx, cy, half_length, half_thickness, angle)`` of the wall in the model."""
        body = self.model.name2id("wall", "body")
        geom = self.model.name2id("wall", "geom")
        w, _, _, z = self.model.body_quat[body]
        angle = 2.0 * np.arctan2(z, w)
        x, y = self.model.body_pos[body, :2]
        half_length, half_thickness = self.model.geom_size[geom, :2]
        return np.array([x, y, half_length, half_thickness, (angle + np.pi) % (2 * np.pi) - np.pi])

    def set_wall(self, wall: np.ndarray) -> None:
        """Move and resize the wall box, keeping the collision bounds consistent with its size."""
        body = self.model.name2id("wall", "body")
        geom = self.model.name2id("wall", "geom")
        half_height = self.model.geom_size[geom, 2]
        self.model.body_pos[body] = [wall[0], wall[1], half_height]
        self.model.body_quat[body] = [np.cos(wall[4] / 2), 0.0, 0.0, np.sin(wall[4] / 2)]
        size = np.array([wall[2], wall[3], half_height])
        self.model.geom_size[geom] = size
        self.model.geom_rbound[geom] = np.linalg.norm(size)
        self.model.geom_aabb[geom] = np.concatenate([np.zeros(3), size])
        # The body's bounding-volume root (one geom at the body origin) is used by the broad phase.
        self.model.bvh_aabb[self.model.body_bvhadr[body]] = np.concatenate([np.zeros(3), size])

    def homography(self) -> np.ndarray:
        """(3, 3) world (x, y) at the puck's height -> pixel (column, row) for the top camera."""
        camera = self.model.name2id(CAMERA, "camera")
        size = self.model.vis.global_.offheight
        return plane_homography(
            self.data.cam_xpos[camera],
            self.data.cam_xmat[camera].reshape(3, 3),
            float(self.model.cam_fovy[camera]),
            bool(self.model.cam_projection[camera] == mujoco.mjtProjection.mjPROJ_ORTHOGRAPHIC),
            size,
            size,
            plane_z=float(self.data.xpos[self.model.name2id("puck", "body"), 2]),
        )

    def puck_pixel(self) -> np.ndarray:
        """(2,) (column, row) pixel coordinates of the puck centre, without rendering."""
        return apply_homography(self.homography(), self.puck_position())

    def render_top(self) -> np.ndarray:
        """(H, W, 3) uint8 top-down image; the camera object is kept (a fresh one costs ~30 ms)."""
        camera = getattr(self, "_top_camera", None)
        if camera is None:
            size = self.model.vis.global_.offheight
            camera = self._top_camera = Camera(self, size, size, camera_id=CAMERA)
        # The camera returns a view of its pixel buffer, which the next render overwrites.
        return camera.render().copy()


class Pushing(base.Task):
    """Push the puck to the goal around the wall; layout random per episode unless pinned."""

    def __init__(
        self,
        sampler: LayoutSampler,
        scene: SceneParams,
        pixels: bool = True,
        random: np.random.RandomState | int | None = None,
    ) -> None:
        super().__init__(random=random)
        self._sampler, self._scene, self._pixels = sampler, scene, pixels
        self._pinned: Layout | None = None
        self._pinned_state: np.ndarray | None = None
        self.layout: Layout | None = None

    @property
    def scene(self) -> SceneParams:
        return self._scene

    @property
    def sampler(self) -> LayoutSampler:
        return self._sampler

    def pin_layout(self, layout: Layout | None, state: np.ndarray | None = None) -> None:
        """Use ``layout`` for every following episode (planning tasks, the generator); None unpins.

        Args:
            layout: the wall, start, goal and pusher home.
            state: optional (S,) physics state (``physics.get_state()``) to start from instead of
                the layout's start and home at rest, e.g. a planning task's ``state``.
        """
        self._pinned, self._pinned_state = layout, state

    def initialize_episode(self, physics: PushingPhysics) -> None:
        if self._pinned is not None:
            layout = self._pinned
        else:
            layout = self._sampler.sample(np.random.default_rng(self.random.randint(2**31)))
        self.layout = layout
        physics.set_wall(layout.wall)
        physics.set_positions(layout.start, layout.home)
        if self._pinned is not None and self._pinned_state is not None:
            physics.set_state(np.asarray(self._pinned_state, dtype=np.float64))
        super().initialize_episode(physics)

    def before_step(self, action: np.ndarray, physics: PushingPhysics) -> None:
        action = np.asarray(action, dtype=np.float64)
        if action.shape != (2,) or not np.all(np.isfinite(action)):
            raise ValueError(f"pushing actions are 2 finite numbers in [-1, 1], got {action!r}")
        physics.set_control(np.clip(action, -1.0, 1.0))

    def goal_distance(self, physics: PushingPhysics) -> float:
        """Shortest-path distance of the puck to the goal around the inflated wall (paper §4.2)."""
        return shortest_path_length(
            physics.puck_position(), self.layout.goal, self.layout.wall, self._scene.puck_radius
        )

    def get_observation(self, physics: PushingPhysics) -> collections.OrderedDict:
        """``pixels`` (H, W, 3) uint8 (if enabled), ``puck``/``pusher`` (2,), ``velocity`` (4,)
        (pusher then puck), ``goal`` (2,), ``wall`` (5,)."""
        obs = collections.OrderedDict()
        if self._pixels:
            obs["pixels"] = physics.render_top()
        obs["puck"] = physics.puck_position()
        obs["pusher"] = physics.pusher_position()
        obs["velocity"] = physics.data.qvel[:4].copy()
        obs["goal"] = np.asarray(self.layout.goal, dtype=np.float64).copy()
        obs["wall"] = np.asarray(self.layout.wall, dtype=np.float64).copy()
        return obs

    def get_reward(self, physics: PushingPhysics) -> float:
        """1 within ``goal_tolerance`` of the goal, falling linearly to 0 at ``REWARD_MARGIN`` beyond.

        The same as ``dm_control.utils.rewards.tolerance(..., sigmoid="linear",
        value_at_margin=0)``, written out because that call costs as much as 10 physics steps.
        """
        excess = self.goal_distance(physics) - self._scene.goal_tolerance
        return 1.0 if excess <= 0.0 else max(0.0, 1.0 - excess / REWARD_MARGIN)


@SUITE.add("benchmarking")
def pushing(
    time_limit: float = DEFAULT_TIME_LIMIT,
    random: np.random.RandomState | int | None = None,
    pixels: bool = True,
    scene: SceneParams | None = None,
    sampler: LayoutSampler | None = None,
    environment_kwargs: dict | None = None,
) -> control.Environment:
    """The pushing environment with 64x64 pixels in its observation (dm_control ``Environment``)."""
    scene = scene or SceneParams()
    sampler = sampler or LayoutSampler(
        arena_half=scene.arena_half, puck_radius=scene.puck_radius, pusher_radius=scene.pusher_radius
    )
    physics = PushingPhysics.from_xml_string(make_model(scene))
    task = Pushing(sampler, scene, pixels=pixels, random=random)
    return control.Environment(
        physics, task, time_limit=time_limit, control_timestep=scene.control_timestep,
        **(environment_kwargs or {}),
    )

