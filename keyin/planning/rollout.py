"""Open-loop rollouts of candidate action sequences on copies of the pushing simulator (paper App. 10).

Both simulators answer the same question: from the environment's *current* physics state, where
does every joint end up after each of ``n`` action sequences ``(n, l, 2)``, one action held for
``action_repeat`` environment steps? Nothing is rendered.

* :class:`BatchRollout` hands all sequences to ``mujoco.rollout`` (C, optionally multi-threaded).
* :class:`LoopRollout` is the reference: per sequence a copy of ``env.physics`` stepped exactly as
  ``dm_control``'s ``Environment.step`` does (``task.before_step``, then ``physics.step`` with the
  environment's substeps). Used by the benchmark and the tests only.

One environment step sets the control once and runs ``substeps = control_timestep / timestep``
physics steps (10 for the pushing scene); ``Pushing.before_step`` maps an action to the control by
clipping it to [-1, 1] (:func:`action_controls` does the same). The two agree bit for bit
(tests/planning/test_rollout.py) when the rollout starts from the full physics state *and* the
solver warm start (``qacc_warmstart``) of the environment.

A copy is ready to step: ``PushingPhysics.after_reset`` (run by ``Physics.copy``) recomputes
``actuator_velocity``, which dm_control's own leaves at 0 (docs/planning.md, "dm_control pitfall").
"""

from __future__ import annotations

from typing import Any, Protocol

import mujoco
import numpy as np
from mujoco import rollout as mj_rollout

FULL_STATE = mujoco.mjtState.mjSTATE_FULLPHYSICS


class Simulator(Protocol):
    """Final joint positions of candidate action sequences from the environment's current state."""

    def final_qpos(self, actions: np.ndarray) -> np.ndarray:
        """(n, l, 2) actions -> (n, nq) ``qpos`` after the last one."""
        ...


def env_substeps(env: Any) -> int:
    """Physics steps per environment step (``control_timestep / timestep``)."""
    return int(round(env.control_timestep() / env.physics.timestep()))


def action_controls(actions: np.ndarray, physics_steps: int) -> np.ndarray:
    """(n, l, 2) actions -> (n, l * physics_steps, 2) controls.

    Each action is clipped to [-1, 1] (as ``Pushing.before_step`` does) and held for
    ``physics_steps`` physics steps.
    """
    return np.repeat(np.clip(np.asarray(actions, dtype=np.float64), -1.0, 1.0), physics_steps, axis=1)


class BatchRollout:
    """All sequences in one ``mujoco.rollout`` call on the environment's (shared) model."""

    def __init__(self, env: Any, action_repeat: int, threads: int = 1) -> None:
        """
        Args:
            env: the dm_control pushing environment whose current state the rollouts start from.
            action_repeat: environment steps per action.
            threads: rollout threads (1 = on the calling thread).
        """
        if threads < 1 or action_repeat < 1:
            raise ValueError(f"threads and action_repeat must be >= 1, got {threads}, {action_repeat}")
        self._physics = env.physics
        self._model = env.physics.model.ptr
        self._physics_steps = action_repeat * env_substeps(env)
        self._data = [mujoco.MjData(self._model) for _ in range(threads)]
        self._pool = mj_rollout.Rollout(nthread=threads if threads > 1 else 0)
        self._qpos = slice(
            mujoco.mj_stateSize(self._model, mujoco.mjtState.mjSTATE_TIME),
            mujoco.mj_stateSize(self._model, mujoco.mjtState.mjSTATE_TIME | mujoco.mjtState.mjSTATE_QPOS),
        )

    def initial_state(self) -> tuple[np.ndarray, np.ndarray]:
        """(1, nstate) full physics state and (1, nv) solver warm start of the environment now."""
        state = np.empty((1, mujoco.mj_stateSize(self._model, FULL_STATE)))
        mujoco.mj_getState(self._model, self._physics.data.ptr, state[0], FULL_STATE)
        return state, self._physics.data.qacc_warmstart[None].copy()

    def final_qpos(self, actions: np.ndarray) -> np.ndarray:
        state, warmstart = self.initial_state()
        states, _ = self._pool.rollout(
            self._model,
            self._data,
            state,
            action_controls(actions, self._physics_steps),
            initial_warmstart=warmstart,
        )
        return states[:, -1, self._qpos].copy()


class LoopRollout:
    """Reference: one ``env.physics`` copy per sequence, stepped in Python like the environment."""

    def __init__(self, env: Any, action_repeat: int) -> None:
        self._env = env
        self._steps = action_repeat
        self._substeps = env_substeps(env)

    def final_qpos(self, actions: np.ndarray) -> np.ndarray:
        finals = []
        for sequence in np.asarray(actions, dtype=np.float64):
            physics = self._env.physics.copy(share_model=True)
            for action in sequence:
                for _ in range(self._steps):
                    self._env.task.before_step(action, physics)
                    physics.step(self._substeps)
            finals.append(physics.data.qpos.copy())
        return np.stack(finals)
