"""Pushing demonstrations as dataset clips (paper §4.1.2, App. 7) and the fixed planning tasks (docs/planning.md).

``PushingGenerator.generate(index, seed)`` runs the rule-based demonstrator of
:mod:`keyin.envs.demonstrator` without rendering, retrying with derived sub-seeds until a demo is
accepted, then renders the accepted demo's saved frames (every ``frame_skip``-th raw frame) with
``renderer``: ``"analytic"`` (:mod:`keyin.envs.render`, numpy, from the recorded positions; MuJoCo's
pixels up to rare depth ties, docs/pushing.md) or ``"mujoco"`` (the top camera through OpenGL, from
the recorded physics states: the reference). A clip is ``L = n_cond + n_future`` saved frames; the
first ``n_cond`` are the conditioning frames. Shorter demos are padded by repeating the last frame
(zero actions), longer ones are truncated and their keyframes beyond the clip dropped. Clip index
``i`` is saved frame ``i``, so with ``n_cond = 1`` future index ``j`` is clip index ``1 + j``.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from keyin.data.generate import ClipMaker, split_seed
from keyin.data.hdf5 import write_shard

N_SUBGOAL_SLOTS = 6  # the ``subgoals`` array is (6, 2) whatever n_pushes is (unused rows repeat the goal)
_ENVS: dict = {}  # one pixel-free environment per generator config and process
RENDERERS = ("analytic", "mujoco")
PLANNING_SPLIT = "planning"  # the fixed planning tasks (docs/planning.md), a split of their own


@dataclass(frozen=True)
class PushingGenerator:
    """Pushing clip generator; plain numbers only, so it pickles into spawn workers.

    The fields mirror ``conf/dataset/pushing.yaml`` (``generator:``), the timing options
    (``push_speed_spread``, ``max_pause_frames``, ``pause_speed``) only in ``pushing_irregular.yaml``;
    docs/pushing.md explains each.
    """

    image_size: int = 64
    n_cond: int = 1
    n_future: int = 30
    max_attempts: int = 100
    renderer: str = "analytic"  # one of RENDERERS
    # scene (keyin.envs.pushing.SceneParams)
    puck_radius: float = 0.06
    pusher_radius: float = 0.04
    puck_mass: float = 0.2
    puck_damping: float = 5.0
    puck_frictionloss: float = 0.1
    pusher_mass: float = 1.0
    pusher_kv: float = 100.0
    v_max: float = 1.0
    timestep: float = 0.01
    contact_timeconst: float = 0.02
    control_timestep: float = 0.1
    arena_half: float = 0.95
    goal_tolerance: float = 0.05
    # layout (keyin.envs.layout.LayoutSampler)
    wall_half_length_min: float = 0.40
    wall_half_length_max: float = 0.45
    wall_half_thickness: float = 0.03
    wall_max_angle_deg: float = 20.0
    wall_offset_min: float = 0.12
    wall_offset_max: float = 0.20
    wall_shift: float = 0.10
    min_end_gap: float = 0.25
    start_distance_min: float = 0.40
    start_distance_max: float = 0.48
    lateral: float = 0.12
    # demonstrator (keyin.envs.demonstrator.DemoParams)
    n_pushes: int = 6
    detour_margin: float = 0.10
    first_share: float = 0.55
    share_jitter: float = 0.20
    lateral_jitter: float = 0.03
    wall_clearance: float = 0.02
    push_speed: float = 0.42
    push_speed_spread: float = 1.0  # the timing options: their defaults are dataset=pushing's regular timing
    max_pause_frames: int = 0
    pause_speed: float = 0.0
    move_speed: float = 1.0
    contact_gap: float = 0.02
    reach_tolerance: float = 0.02
    frame_skip: int = 2
    min_push_frames: int = 4
    max_push_frames: int = 6

    def __post_init__(self) -> None:
        if self.renderer not in RENDERERS:
            raise ValueError(f"renderer must be one of {RENDERERS}, got {self.renderer!r}")

    @property
    def clip_length(self) -> int:
        return self.n_cond + self.n_future

    def _parts(self) -> tuple[Any, Any, Any]:
        from keyin.envs.demonstrator import DemoParams
        from keyin.envs.layout import LayoutSampler
        from keyin.envs.pushing import SceneParams

        fields = asdict(self)

        def pick(cls: type, **extra: Any) -> Any:
            names = cls.__dataclass_fields__
            return cls(**{k: v for k, v in fields.items() if k in names}, **extra)

        scene = pick(SceneParams)
        sampler = pick(
            LayoutSampler,
            wall_half_length=(self.wall_half_length_min, self.wall_half_length_max),
            wall_offset=(self.wall_offset_min, self.wall_offset_max),
            start_distance=(self.start_distance_min, self.start_distance_max),
        )
        return scene, sampler, pick(DemoParams)

    def environment(self) -> Any:
        """This process's pixel-free dm_control environment for this config (built once)."""
        if self not in _ENVS:
            from keyin.envs.pushing import pushing

            scene, sampler, _ = self._parts()
            _ENVS[self] = pushing(random=0, pixels=False, scene=scene, sampler=sampler)
        return _ENVS[self]

    def demo(self, index: int, seed: int) -> tuple[Any, int]:
        """The accepted demo for ``seed + index`` and the number of attempts it took.

        Attempt ``k`` draws everything from ``SeedSequence(seed + index, spawn_key=(k,))``.
        """
        from keyin.envs.demonstrator import run_demo

        env = self.environment()
        _, sampler, params = self._parts()
        for attempt in range(self.max_attempts):
            rng = np.random.default_rng(np.random.SeedSequence(seed + index, spawn_key=(attempt,)))
            demo = run_demo(env, sampler.sample(rng), rng, params)
            if demo is not None:
                return demo, attempt + 1
        raise RuntimeError(
            f"no accepted pushing demo for seed {seed} + index {index} in {self.max_attempts} attempts; "
            f"loosen min/max_push_frames or raise max_attempts"
        )

    def demos_from(self, layout: Any, count: int, seed: int) -> list[Any]:
        """Up to ``count`` accepted demos on one :class:`keyin.envs.layout.Layout` (each with its own
        detour side and subgoals), attempt ``k`` drawn from ``SeedSequence(seed, spawn_key=(k,))``,
        at most ``max_attempts * count`` attempts."""
        from keyin.envs.demonstrator import run_demo

        env = self.environment()
        params = self._parts()[2]
        demos, attempt = [], 0
        while len(demos) < count and attempt < self.max_attempts * count:
            rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(attempt,)))
            demo = run_demo(env, layout, rng, params)
            if demo is not None:
                demos.append(demo)
            attempt += 1
        return demos

    def render_states(self, states: np.ndarray) -> np.ndarray:
        """(K, S) physics states -> (K, H, W, 3) uint8 top-camera frames rendered by MuJoCo."""
        physics = self.environment().physics
        frames = np.empty((len(states), self.image_size, self.image_size, 3), np.uint8)
        for k, state in enumerate(states):
            with physics.reset_context():
                physics.set_state(state)
            frames[k] = physics.render_top()
        return frames

    def render_demo(self, demo: Any, frames: np.ndarray) -> np.ndarray:
        """(K,) raw frame indices of ``demo`` -> (K, H, W, 3) uint8 top-camera frames by ``renderer``."""
        if self.renderer == "mujoco":
            self.environment().physics.set_wall(demo.layout.wall)
            return self.render_states(demo.states[frames])
        return self.render_positions(demo.layout.wall, demo.puck[frames], demo.pusher[frames])

    def render_positions(self, wall: np.ndarray, puck: np.ndarray, pusher: np.ndarray) -> np.ndarray:
        """(K, H, W, 3) uint8 top-camera frames of the scene with ``wall`` (5,) and the (K, 2) puck
        and pusher positions, by the analytic renderer (equal to MuJoCo's, docs/pushing.md)."""
        from keyin.envs.render import render_top

        return render_top(self._parts()[0], wall, puck, pusher)

    def generate(self, index: int, seed: int) -> tuple[dict[str, np.ndarray], int]:
        """One clip, deterministic in ``seed + index``.

        Returns:
            arrays (L = n_cond + n_future): ``frames`` (L, H, W, 3) uint8, ``length`` () int32 valid
                frames, ``keyframes`` (L,) bool (the last saved frame of each push), ``actions``
                (L-1, 2) float32 (mean of the two raw actions per saved step; zero in padding),
                ``puck``, ``pusher`` (L, 2) float32, ``wall`` (5,) float32, ``goal`` (2,) float32,
                ``subgoals`` (6, 2) float32, ``completions`` (n_pushes,) int32 saved frame of each
                push completion (may exceed L-1), ``side`` () int8 detour side.
            attempts: demos drawn until one was accepted (1 = no rejection).
        """
        demo, attempts = self.demo(index, seed)
        skip, length = self.frame_skip, self.clip_length
        saved = np.arange(0, len(demo.states), skip)
        valid = min(len(saved), length)
        keep = saved[:valid]
        frames = self.render_demo(demo, keep)
        pad = length - valid
        actions = demo.actions.reshape(-1, skip, 2).mean(axis=1)[: valid - 1]
        completions = demo.saved_completions(skip)
        keyframes = np.zeros(length, dtype=bool)
        keyframes[completions[completions < length]] = True
        subgoals = np.concatenate(
            [demo.subgoals, np.repeat(demo.subgoals[-1:], max(0, N_SUBGOAL_SLOTS - len(demo.subgoals)), 0)]
        )[:N_SUBGOAL_SLOTS]

        def padded(values: np.ndarray) -> np.ndarray:
            return np.concatenate([values, np.repeat(values[-1:], pad, axis=0)])

        arrays = {
            "frames": padded(frames),
            "length": np.int32(valid),
            "keyframes": keyframes,
            "actions": np.concatenate([actions, np.zeros((pad, 2))]).astype(np.float32),
            "puck": padded(demo.puck[keep]).astype(np.float32),
            "pusher": padded(demo.pusher[keep]).astype(np.float32),
            "wall": demo.layout.wall.astype(np.float32),
            "goal": demo.layout.goal.astype(np.float32),
            "subgoals": subgoals.astype(np.float32),
            "completions": completions.astype(np.int32),
            "side": np.int8(demo.side),
        }
        return arrays, attempts

    def planning_task(self, index: int, seed: int) -> dict[str, np.ndarray]:
        """A planning task from an accepted demo (docs/planning.md): start in the demo's start state,
        reach the demo's final puck position.

        Returns:
            ``state`` (S,) float64 physics state (``physics.set_state``), ``start_image`` and
            ``goal_image`` (H, W, 3) uint8 (the goal image is the demo's last frame), ``goal`` (2,)
            and ``start`` (2,) puck positions, ``wall`` (5,), ``layout`` (11,)
            (:meth:`keyin.envs.layout.Layout.as_array`, whose goal is the demo's final puck
            position), ``initial_distance`` () shortest path start -> goal, and the demo's own
            subgoals as its keyframes show them: ``subgoal_frames`` (P, H, W, 3) uint8, the saved
            frame that completes each of the P pushes (the clips' ``keyframes``), and
            ``subgoal_puck`` (P, 2) the puck in them.
        """
        return self._task_arrays(self.demo(index, seed)[0])

    def planning_clip(self, index: int, seed: int) -> tuple[dict[str, np.ndarray], int]:
        """:meth:`planning_task` as a clip of the ``planning`` split (``keyin-generate``): ``frames``
        (2, H, W, 3) the start and the goal image, ``length`` 2, the other arrays as they are;
        and the demos drawn until one was accepted."""
        demo, attempts = self.demo(index, seed)
        task = self._task_arrays(demo)
        frames = np.stack([task.pop("start_image"), task.pop("goal_image")])
        return {"frames": frames, "length": np.int32(2), **task}, attempts

    @property
    def split_makers(self) -> dict[str, ClipMaker]:
        """Splits whose clips are not demos (``keyin.data.generate``): the planning tasks."""
        return {PLANNING_SPLIT: self.planning_clip}

    def _task_arrays(self, demo: Any) -> dict[str, np.ndarray]:
        """:meth:`planning_task`'s arrays from an accepted demo."""
        from keyin.envs.geometry import shortest_path_length
        from keyin.envs.layout import Layout

        last = len(demo.states) - 1
        completions = np.minimum(demo.saved_completions(self.frame_skip) * self.frame_skip, last)  # raw frames
        images = self.render_demo(demo, np.concatenate([[0, last], completions]))
        goal = demo.puck[-1]
        layout = Layout(demo.layout.wall, demo.layout.start, goal, demo.layout.home)
        return {
            "state": demo.states[0].copy(),
            "start_image": images[0],
            "goal_image": images[1],
            "start": demo.puck[0].copy(),
            "goal": goal.copy(),
            "wall": demo.layout.wall.copy(),
            "layout": layout.as_array(),
            "initial_distance": np.float64(
                shortest_path_length(demo.puck[0], goal, demo.layout.wall, self.puck_radius)
            ),
            "subgoal_frames": images[2:],
            "subgoal_puck": demo.puck[completions].copy(),
        }


def write_planning_tasks(path: Path, generator: PushingGenerator, n: int = 240, seed: int = 0) -> str:
    """Write ``n`` planning tasks as one keyin shard (``split = "planning"``) and return its SHA-256.

    Each task is a 2-frame clip (:meth:`PushingGenerator.planning_clip`): ``frames[:, 0]`` the start
    image (the conditioning frame, ``n_cond = 1``), ``frames[:, 1]`` the goal image; ``length`` is
    2. Further arrays: ``state`` (n, S), ``start``/``goal`` (n, 2), ``wall`` (n, 5), ``layout``
    (n, 11), ``initial_distance`` (n,), ``subgoal_frames`` (n, P, H, W, 3), ``subgoal_puck``
    (n, P, 2). Task ``i`` uses ``split_seed(seed, "planning") + i``, a seed range no
    train/val/test clip uses; ``keyin-generate dataset=pushing 'splits={planning: 240}'`` writes
    the same tasks into the dataset folder.
    """
    base = split_seed(seed, PLANNING_SPLIT)
    tasks = [generator.planning_clip(i, base)[0] for i in range(n)]
    arrays = {name: np.stack([task[name] for task in tasks]) for name in tasks[0]}
    attrs = {"generator": type(generator).__name__, "config": asdict(generator), "seed": base,
             "split": PLANNING_SPLIT, "n_cond": 1}
    return write_shard(Path(path), arrays, attrs)
