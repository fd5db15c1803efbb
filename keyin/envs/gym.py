"""Gymnasium view of the dm_control pushing task: ``gymnasium.make("keyin/Pushing-v0")``.

Observations are a dict: ``pixels`` (64, 64, 3) uint8 and the states of
:meth:`keyin.envs.pushing.Pushing.get_observation`. Each ``reset`` draws the layout from
Gymnasium's ``np_random`` (so ``reset(seed=s)`` is reproducible); ``options={"layout": layout}``
(a :class:`keyin.envs.layout.Layout` or its (11,) array) uses that layout instead, and
``options["state"]`` an (S,) physics state to start from (planning tasks). The episode is truncated at
the dm_control time limit (12 s = 120 steps); it never terminates early. Out-of-range actions are
clipped to ``[-1, 1]`` by the task, non-finite ones raise ``ValueError``.
"""

from __future__ import annotations

from typing import Any

import gymnasium
import numpy as np
from gymnasium import spaces

from keyin.envs import pushing
from keyin.envs.layout import Layout

ENV_ID = "keyin/Pushing-v0"


class PushingGymEnv(gymnasium.Env):
    """Gymnasium wrapper around ``keyin.envs.pushing.pushing()``."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10}

    def __init__(self, render_mode: str | None = None, **task_kwargs: Any) -> None:
        self.render_mode = render_mode
        self._env = pushing.pushing(random=0, pixels=True, **task_kwargs)
        self._sampler = self._env.task.sampler
        size = self._env.physics.model.vis.global_.offheight
        unbounded = {"shape": None, "low": -np.inf, "high": np.inf, "dtype": np.float64}
        self.observation_space = spaces.Dict(
            {
                "pixels": spaces.Box(0, 255, (size, size, 3), np.uint8),
                **{
                    name: spaces.Box(**{**unbounded, "shape": (dim,)})
                    for name, dim in (("puck", 2), ("pusher", 2), ("velocity", 4), ("goal", 2), ("wall", 5))
                },
            }
        )
        self.action_space = spaces.Box(-1.0, 1.0, (2,), np.float32)
        self._last_pixels: np.ndarray | None = None

    def _convert(self, observation: dict) -> dict[str, np.ndarray]:
        self._last_pixels = observation["pixels"]
        return {name: np.asarray(value) for name, value in observation.items()}

    def _info(self) -> dict[str, Any]:
        return {
            "goal_distance": self._env.task.goal_distance(self._env.physics),
            "layout": self._env.task.layout,
        }

    def reset(self, *, seed: int | None = None, options: dict | None = None) -> tuple[dict, dict]:
        super().reset(seed=seed)
        layout = (options or {}).get("layout")
        if layout is None:
            layout = self._sampler.sample(self.np_random)
        elif not isinstance(layout, Layout):
            layout = Layout.from_array(np.asarray(layout))
        self._env.task.pin_layout(layout, (options or {}).get("state"))
        step = self._env.reset()
        return self._convert(step.observation), self._info()

    def step(self, action: np.ndarray) -> tuple[dict, float, bool, bool, dict]:
        step = self._env.step(action)
        return self._convert(step.observation), float(step.reward), False, bool(step.last()), self._info()

    def render(self) -> np.ndarray | None:
        if self.render_mode != "rgb_array":
            return None
        if self._last_pixels is None:
            return self._env.physics.render_top()
        return self._last_pixels

    @property
    def physics(self) -> pushing.PushingPhysics:
        """The underlying physics (``get_state``/``set_state`` for planners)."""
        return self._env.physics


def register() -> None:
    """Register ``keyin/Pushing-v0`` once."""
    if ENV_ID not in gymnasium.registry:
        gymnasium.register(id=ENV_ID, entry_point="keyin.envs.gym:PushingGymEnv")
