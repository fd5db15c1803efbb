"""Environments: the pushing task on dm_control, its demonstrator and the wall geometry.

``keyin.envs.load(name, seed)`` builds a registered task like ``dm_control.suite.load``; importing
this package also registers ``keyin/Pushing-v0`` with Gymnasium (when Gymnasium is installed).
"""

from __future__ import annotations

import os

# Headless rendering must be chosen before dm_control (or mujoco's GL backends) is imported.
os.environ.setdefault("MUJOCO_GL", "egl")

from dm_control.rl import control  # noqa: E402

from keyin.envs import pushing  # noqa: E402

# Every task module keeps its factories in its own TaggedTasks ``SUITE`` (dm_control's layout).
_SUITES = (pushing.SUITE,)
TASK_NAMES: tuple[str, ...] = tuple(name for suite in _SUITES for name in suite)


def load(name: str, seed: int | None = None, **kwargs) -> control.Environment:
    """Build a registered task.

    Args:
        name: one of ``TASK_NAMES`` (``"pushing"``).
        seed: seeds the task's layout sampling (``None``: fresh entropy).
        **kwargs: passed to the task factory, e.g. ``pixels=False``, ``time_limit=``.
    """
    for suite in _SUITES:
        if name in suite:
            return suite[name](random=seed, **kwargs)
    raise ValueError(f"unknown environment {name!r}; registered: {', '.join(TASK_NAMES)}")


try:  # Gymnasium is optional (the `sim` extra); the dm_control API works without it.
    import gymnasium  # noqa: F401
except ImportError:  # pragma: no cover
    pass
else:
    from keyin.envs import gym as _gym  # noqa: E402

    _gym.register()
