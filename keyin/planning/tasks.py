"""The fixed pushing planning tasks (docs/planning.md): read from the ``planning`` split, restored in
the environment.

``keyin-generate dataset=pushing 'splits={planning: 240}'`` writes them
(:meth:`keyin.data.pushing.PushingGenerator.planning_clip`); each task starts in a demonstration's
first state and asks for the puck where that demonstration ended.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from keyin.data.hdf5 import inspect_shard, load_arrays
from keyin.data.pushing import PLANNING_SPLIT, PushingGenerator
from keyin.envs.layout import Layout
from keyin.errors import DatasetFormatError

TASK_ARRAYS = ("frames", "state", "layout", "initial_distance")


@dataclass(frozen=True)
class PlanningTask:
    """One task.

    Attributes:
        index: its place in the planning split (its seed is the split's seed + index).
        state: (S,) physics state to start from.
        layout: (11,) :meth:`Layout.as_array`; its goal is the demonstration's final puck.
        start_image, goal_image: (H, W, 3) uint8.
        initial_distance: shortest path around the wall from the start to the goal.
        subgoal_frames: (P, H, W, 3) uint8, the demonstration's keyframes (one per push), or None
            in a task file without them.
    """

    index: int
    state: np.ndarray
    layout: np.ndarray
    start_image: np.ndarray
    goal_image: np.ndarray
    initial_distance: float
    subgoal_frames: np.ndarray | None = None


def read_tasks(files: Sequence[Path]) -> tuple[list[PlanningTask], dict[str, Any]]:
    """The tasks of the planning split's shards, in index order, and the generator config that made
    them (the scene the environment must reproduce).

    Raises:
        DatasetFormatError: a shard of another split, one without the task arrays, or shards made
            with different generator configs.
    """
    tasks, config = [], None
    for path in files:
        info = inspect_shard(path)
        arrays = load_arrays(path)
        missing = [name for name in TASK_ARRAYS if name not in arrays]
        if info.split != PLANNING_SPLIT or missing:
            raise DatasetFormatError(
                f"{path} holds no planning tasks (split {info.split!r}, lacks {', '.join(missing) or 'nothing'}); "
                f"write them with keyin-generate dataset=pushing 'splits={{planning: 240}}'"
            )
        if config is not None and info.config != config:
            raise DatasetFormatError(f"{path} was generated with another config than {files[0]}; regenerate the split")
        config = info.config
        first = info.first_index or 0
        subgoals = arrays.get("subgoal_frames")
        for row in range(info.n):
            tasks.append(
                PlanningTask(
                    index=first + row,
                    state=arrays["state"][row],
                    layout=arrays["layout"][row],
                    start_image=arrays["frames"][row, 0],
                    goal_image=arrays["frames"][row, -1],
                    initial_distance=float(arrays["initial_distance"][row]),
                    subgoal_frames=None if subgoals is None else subgoals[row],
                )
            )
    return sorted(tasks, key=lambda task: task.index), dict(config or {})


def task_generator(config: Mapping[str, Any]) -> PushingGenerator:
    """The generator (and so the scene) a task file's ``config`` attribute describes."""
    return PushingGenerator(**{key: value for key, value in config.items() if key != "_target_"})


def start_task(env: Any, task: PlanningTask) -> None:
    """Reset the dm_control pushing environment to the task's layout and start state."""
    env.task.pin_layout(Layout.from_array(task.layout), task.state)
    env.reset()
