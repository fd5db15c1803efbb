"""Low-level CEM servo on the ground-truth simulator (paper App. 10 / Alg. 4, Table 3).

Each servo step:

1. observe the puck's pixel (:func:`puck_observer`) and switch subgoal (:func:`advance_subgoal`):
   past every subgoal it is within ``subgoal_threshold_px`` of, or to the next one after
   ``max_steps_per_subgoal`` steps on it; never past the last one (the goal);
2. stop if the last subgoal is within ``goal_threshold_px``;
3. CEM over ``horizon`` actions ``(horizon, 2)`` from ``N(0, init_std²)`` (re-initialised every
   step), samples clipped to ``±max_action``; cost = pixel distance between the puck observed after
   the last action (simulated from the current state, :mod:`keyin.planning.rollout`) and the
   subgoal's puck pixel (final-step cost only);
4. execute the first action of the best plan: the lowest cost over all CEM iterations (the paper
   takes the best of the last iteration; the rollouts are deterministic, so the best seen is at
   least as good by the same cost).

A servo step is one *saved frame* of the dataset: the action is held for ``action_repeat = 2``
environment steps (docs/planning.md, "The servo"), so ``max_timesteps = 60`` servo steps are the environment's 12 s
time limit, ``max_steps_per_subgoal = 10`` is about twice a demonstration push (4-6 saved frames),
and a plan of ``horizon = 8`` actions looks 1.6 s ahead. Subgoal pixels come from colour
segmentation of the subgoal images (:func:`subgoal_pixels`), as for a predicted keyframe.

How the servo sees the puck, in the current state and in a candidate's final state
(``observe``, config ``servo_observe``):

* ``state`` (default, fast): the true puck centre through the camera homography, nothing rendered;
* ``pixels`` (the paper's): the puck centroid segmented by colour from the 64 x 64 top-camera
  frame of the state, drawn by the analytic renderer (:mod:`keyin.envs.render`, MuJoCo's pixels),
  the whole CEM batch at once. A frame without a visible puck has no position: a candidate ending
  so costs infinity, and a current frame so reaches no subgoal (in a task the border keeps the
  puck in view and it stands higher than every box and the pusher, so neither is expected).
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from keyin.envs.geometry import apply_homography
from keyin.envs.pushing import PushingPhysics, SceneParams
from keyin.envs.render import render_top
from keyin.envs.segmentation import puck_centroid
from keyin.errors import ConfigError
from keyin.planning.cem import CEMParams, cem
from keyin.planning.rollout import BatchRollout, Simulator

# conf/planner keys -> ServoParams fields
CONFIG_KEYS = {
    "servo_horizon": "horizon",
    "servo_samples": "samples",
    "elites": "elites",
    "cem_iterations": "iterations",
    "max_action": "max_action",
    "servo_init_std": "init_std",
    "max_timesteps": "max_timesteps",
    "max_steps_per_subgoal": "max_steps_per_subgoal",
    "servo_action_repeat": "action_repeat",
    "subgoal_threshold_px": "subgoal_threshold_px",
    "goal_threshold_px": "goal_threshold_px",
    "servo_threads": "threads",
    "servo_observe": "observe",
}
# How the servo sees the puck (module docstring).
OBSERVATIONS = ("state", "pixels")
# (n, nq) joint positions -> (n, 2) puck pixels (column, row), NaN where no puck is seen.
PuckObserver = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class ServoParams:
    """The servo's constants (``conf/planner/*.yaml``, names in :data:`CONFIG_KEYS`)."""

    horizon: int = 8  # l, actions per plan
    samples: int = 200
    elites: int = 10
    iterations: int = 3
    max_action: float = 1.0  # a_max: samples are clipped to ±max_action
    init_std: float = 1.0  # the action distribution every step starts as N(0, init_std²)
    max_timesteps: int = 60  # T_max, servo steps
    max_steps_per_subgoal: int = 10  # T_s,max, servo steps
    action_repeat: int = 2  # environment steps per servo step (one saved frame)
    subgoal_threshold_px: float = 3.0  # reach radius of a subgoal (3 px = 0.094 units)
    goal_threshold_px: float = 3.0  # stop within this of the last subgoal (0: never stop early)
    threads: int = 1  # mujoco.rollout threads
    observe: str = "state"  # one of OBSERVATIONS

    def __post_init__(self) -> None:
        if self.observe not in OBSERVATIONS:
            raise ConfigError(f"planner.servo_observe={self.observe!r} must be one of {', '.join(OBSERVATIONS)}")

    @classmethod
    def from_config(cls, config: Mapping[str, Any]) -> "ServoParams":
        """Pick the servo's keys out of a planner config (other keys are ignored)."""
        return cls(**{field: config[key] for key, field in CONFIG_KEYS.items() if key in config})

    def cem_params(self) -> CEMParams:
        return CEMParams(self.samples, self.elites, self.iterations, -self.max_action, self.max_action)


@dataclass(frozen=True)
class ServoTrajectory:
    """One servo episode with T executed servo steps.

    Attributes:
        puck, pusher: (T + 1, 2) world positions at the start and after every step.
        subgoal: (T,) index (into the given subgoals) each step planned for.
        actions: (T, 2) executed actions.
        plan_cost: (T,) predicted pixel distance to the subgoal of the executed plan (inf if no
            candidate's final frame showed the puck).
        reached_goal: the final puck, as the servo sees it, is within ``goal_threshold_px`` of the
            last subgoal (the servo stops as soon as it is).
        final_error: shortest path around the wall (inflated by the puck radius) from the final puck
            to the task's goal, world units (paper §4.2).
    """

    puck: np.ndarray
    pusher: np.ndarray
    subgoal: np.ndarray
    actions: np.ndarray
    plan_cost: np.ndarray
    reached_goal: bool
    final_error: float


def subgoal_pixels(images: np.ndarray) -> np.ndarray:
    """(K, H, W, 3) subgoal images -> (K, 2) puck centroids (column, row); NaN where no puck shows."""
    centroids, _ = puck_centroid(np.asarray(images))
    return np.asarray(centroids, dtype=np.float64)


def advance_subgoal(
    index: int, steps_on: int, distances: np.ndarray, threshold: float, max_steps: int
) -> int:
    """The subgoal to plan for now.

    Args:
        index: the current subgoal.
        steps_on: servo steps already spent on it.
        distances: (K,) pixel distance of the puck to every subgoal; the last is the goal.
        threshold: reach radius in pixels.
        max_steps: steps after which the current subgoal is given up.
    """
    last = len(distances) - 1
    if index < last and steps_on >= max_steps:
        index += 1
    while index < last and distances[index] < threshold:
        index += 1
    return index


def projected_puck(homography: np.ndarray, qpos: np.ndarray) -> np.ndarray:
    """(n, nq) joint positions -> (n, 2) pixels of the true puck centres through the homography (3, 3)."""
    return apply_homography(homography, qpos[:, PushingPhysics.PUCK])


def segmented_puck(scene: SceneParams, wall: np.ndarray, qpos: np.ndarray) -> np.ndarray:
    """(n, nq) joint positions -> (n, 2) puck centroids segmented from their rendered frames.

    All ``n`` top-camera frames of the scene with ``wall`` (5,) are drawn in one
    :func:`keyin.envs.render.render_top` call; NaN where a frame shows no puck.
    """
    frames = render_top(scene, wall, qpos[:, PushingPhysics.PUCK], qpos[:, PushingPhysics.PUSHER])
    return subgoal_pixels(frames)


def puck_observer(env: Any, observe: str) -> PuckObserver:
    """How the servo sees the puck in ``env``'s scene (``observe`` in :data:`OBSERVATIONS`)."""
    if observe == "pixels":
        return functools.partial(segmented_puck, env.task.scene, env.physics.wall())
    return functools.partial(projected_puck, env.physics.homography())


def pixel_cost(pixels: np.ndarray, targets: np.ndarray) -> np.ndarray:
    """(...) pixel distances between puck pixels and targets (..., 2), broadcast; inf where NaN (not seen)."""
    distance = np.linalg.norm(pixels - targets, axis=-1)
    return np.where(np.isnan(distance), np.inf, distance)


def execute(env: Any, action: np.ndarray, repeat: int) -> bool:
    """Hold ``action`` for ``repeat`` environment steps; True if the episode ended (time limit)."""
    for _ in range(repeat):
        if env.step(action).last():
            return True
    return False


def run_servo(
    env: Any,
    targets: np.ndarray,
    params: ServoParams,
    rng: np.random.Generator,
    simulator: Simulator | None = None,
) -> ServoTrajectory:
    """Servo the environment from its current state through the subgoals.

    Args:
        env: the dm_control pushing environment at the task's start (``pixels=False`` is enough:
            ``params.observe = "pixels"`` draws its frames with the analytic renderer).
        targets: (K, 2) subgoal puck pixels (:func:`subgoal_pixels`), the last one the goal's. A
            subgoal without a visible puck (NaN) is skipped; the goal must show the puck.
        params: the servo's constants.
        rng: the CEM's randomness.
        simulator: where candidate plans are rolled out; default a :class:`BatchRollout`.
    """
    targets = np.asarray(targets, dtype=np.float64)
    if len(targets) == 0 or np.isnan(targets[-1]).any():
        raise ValueError("the last subgoal (the goal) must show the puck")
    visible = np.flatnonzero(~np.isnan(targets).any(axis=-1))
    simulator = simulator or BatchRollout(env, params.action_repeat, params.threads)
    physics = env.physics
    observe = puck_observer(env, params.observe)
    cem_params = params.cem_params()
    shape = (params.horizon, 2)
    puck, pusher = [physics.puck_position()], [physics.pusher_position()]
    subgoals, actions, costs = [], [], []
    index = steps_on = 0  # into ``visible``
    for _ in range(params.max_timesteps):
        distances = pixel_cost(observe(physics.data.qpos[None]), targets[visible])
        switched = advance_subgoal(
            index, steps_on, distances, params.subgoal_threshold_px, params.max_steps_per_subgoal
        )
        if switched != index:
            index, steps_on = switched, 0
        if index == len(visible) - 1 and distances[index] < params.goal_threshold_px:
            break
        target = targets[visible[index]]
        plan = cem(
            lambda plans: pixel_cost(observe(simulator.final_qpos(plans)), target),
            np.zeros(shape),
            np.full(shape, params.init_std),
            cem_params,
            rng,
        )
        ended = execute(env, plan.best[0], params.action_repeat)
        steps_on += 1
        subgoals.append(visible[index])
        actions.append(plan.best[0])
        costs.append(plan.best_cost)
        puck.append(physics.puck_position())
        pusher.append(physics.pusher_position())
        if ended:
            break
    goal_px = pixel_cost(observe(physics.data.qpos[None]), targets[-1])[0]
    return ServoTrajectory(
        puck=np.stack(puck),
        pusher=np.stack(pusher),
        subgoal=np.asarray(subgoals, dtype=np.int64),
        actions=np.asarray(actions, dtype=np.float64).reshape(-1, 2),
        plan_cost=np.asarray(costs, dtype=np.float64),
        reached_goal=bool(goal_px < params.goal_threshold_px),
        final_error=env.task.goal_distance(physics),
    )
