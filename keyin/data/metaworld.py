"""Meta-World's scripted experts as dataset clips, labelled with the experts' own phase switches
(docs/metaworld.md; the episodes: :mod:`keyin.envs.metaworld`).

``MetaWorldGenerator.generate(index, seed)`` draws a task from ``tasks``, plays its expert with varied
timing (random hand start, per-episode speed cap, pauses at new phases) and keeps every
``frame_skip``-th observation, rendered at ``image_size`` by ``camera``, until ``tail_frames`` saved
frames after the first success. The keyframes are the saved frames nearest to each phase switch the
expert holds ``hold_steps`` steps, and the first success. An episode that does not succeed within the
clip is redrawn (``attempts``); shorter clips are padded by repeating the last frame.
"""

from __future__ import annotations

import copy
import os
from dataclasses import dataclass
from typing import Any

import numpy as np

from keyin.envs.metaworld import PhaseTracer, Timing, check_tasks, debounced_switches, expert, make_env, run_episode

# the experts that succeed under every timing lever (assembly and peg-insert-side re-enter their phases and often fail)
DEFAULT_TASKS = ("pick-place-v3", "push-v3", "door-open-v3", "drawer-open-v3", "button-press-topdown-v3")
CAMERAS_UPSIDE_DOWN = ("corner", "corner2", "corner3")  # Meta-World's corner cameras render turned by 180°
_WORLDS: dict = {}  # per process: task -> (env, tracer, renderer)


@dataclass(frozen=True)
class MetaWorldGenerator:
    tasks: tuple[str, ...] = DEFAULT_TASKS
    image_size: int = 64
    camera: str = "corner"
    n_cond: int = 1
    n_future: int = 25
    frame_skip: int = 8           # env steps per saved frame
    tail_frames: int = 2          # saved frames kept after the first success
    hold_steps: int = 3           # a phase switch counts once the new phase is held this many env steps
    hand_low: tuple[float, float, float] | None = (-0.2, 0.45, 0.1)
    hand_high: tuple[float, float, float] | None = (0.2, 0.75, 0.3)
    speed_min: float = 0.4
    max_pause: int = 16           # env steps
    max_attempts: int = 20

    def __post_init__(self) -> None:
        if not self.tasks:
            raise ValueError("tasks must name at least one Meta-World task, e.g. [pick-place-v3]")
        if self.frame_skip < 1 or self.n_future < 1 or self.tail_frames < 0:
            raise ValueError("frame_skip and n_future must be >= 1 and tail_frames >= 0")
        for name in ("tasks", "hand_low", "hand_high"):  # lists from a config become hashable tuples
            value = getattr(self, name)
            object.__setattr__(self, name, None if value is None else tuple(value))
        check_tasks(self.tasks)

    @property
    def timing(self) -> Timing:
        return Timing(self.hand_low, self.hand_high, self.speed_min, self.max_pause)

    @property
    def clip_length(self) -> int:
        return self.n_cond + self.n_future

    @property
    def max_steps(self) -> int:
        """Env steps that fill a clip: (L - 1) saved frames after the first."""
        return (self.clip_length - 1) * self.frame_skip

    def world(self, task: str) -> tuple[Any, PhaseTracer, Any]:
        """This process's environment, phase tracer and renderer of ``task`` (built once)."""
        key = (self, task)
        if key not in _WORLDS:
            os.environ.setdefault("MUJOCO_GL", "egl")
            import mujoco

            env = make_env(task, self.max_steps + 1)
            env.model.vis.quality.shadowsize = 0
            env.model.vis.quality.offsamples = 0
            _WORLDS[key] = env, PhaseTracer(expert(task)), mujoco.Renderer(env.model, self.image_size, self.image_size)
        return _WORLDS[key]

    def render(self, renderer: Any, data: Any) -> np.ndarray:
        """(H, W, 3) uint8 of the scene in ``data`` (an env's ``MjData`` or a copy of it)."""
        renderer.update_scene(data, camera=self.camera)
        image = renderer.render()
        return np.ascontiguousarray(image[::-1, ::-1] if self.camera in CAMERAS_UPSIDE_DOWN else image)

    def generate(self, index: int, seed: int) -> tuple[dict[str, np.ndarray], int]:
        """One clip, deterministic in ``seed + index``.

        Returns:
            arrays (L = n_cond + n_future): ``frames`` (L, H, W, 3) uint8, ``length`` () int32 valid
                frames, ``keyframes`` (L,) bool (the saved frames nearest to each kept phase switch
                and to the first success), ``phases`` (L,) int8 (the expert's branch at each saved
                frame), ``hand`` (L, 3) float32, ``task`` () int8 (an index into ``tasks``),
                ``success_step`` () int32 env step of the first success.
            attempts: episodes drawn until one succeeded inside the clip (1 = no rejection).
        Raises:
            RuntimeError: no episode succeeded within the clip in ``max_attempts`` draws.

        The task is drawn from ``seed + index`` alone, so rejected episodes do not bias the task mix.
        """
        length = self.clip_length
        task_index = int(np.random.default_rng(seed + index).integers(len(self.tasks)))
        env, tracer, renderer = self.world(self.tasks[task_index])
        for attempt in range(self.max_attempts):
            rng = np.random.default_rng(np.random.SeedSequence(seed + index, spawn_key=(attempt,)))
            episode = run_episode(  # the saved frames' physics copied; rendered only if the episode is kept
                env, tracer, self.timing, rng, self.max_steps, self.tail_frames * self.frame_skip,
                lambda e: copy.copy(e.data), self.frame_skip,
            )
            if episode.success_step is not None and episode.success_step <= self.max_steps - self.tail_frames * self.frame_skip:
                break
        else:
            raise RuntimeError(
                f"clip {index} ({self.tasks[task_index]}): no expert episode succeeded within {self.max_steps} env steps in {self.max_attempts} "
                f"draws; raise n_future or frame_skip, or drop the task"
            )
        frames = [self.render(renderer, data) for data in episode.captures]
        valid = len(frames)
        switch_steps = debounced_switches(episode.phases, self.hold_steps) + [episode.success_step]
        keyframes = np.zeros(length, dtype=bool)
        keyframes[np.minimum(np.rint(np.array(switch_steps) / self.frame_skip).astype(int), valid - 1)] = True
        saved = np.arange(valid) * self.frame_skip
        phases = np.append(episode.phases, episode.phases[-1])[saved]  # the phase acting on each saved frame
        pad = length - valid

        def padded(values: np.ndarray) -> np.ndarray:
            return np.concatenate([values, np.repeat(values[-1:], pad, axis=0)])

        arrays = {
            "frames": padded(np.stack(frames)),
            "length": np.int32(valid),
            "keyframes": keyframes,
            "phases": padded(phases).astype(np.int8),
            "hand": padded(episode.hand[saved]).astype(np.float32),
            "task": np.int8(task_index),
            "success_step": np.int32(episode.success_step),
        }
        return arrays, attempt + 1
