"""High-level planners: the subgoal images a task's servo works through (paper Table 2).

A high-level planner is a callable ``(start_image, goal_image, task, rng) -> Subgoals``: (K, H, W, 3)
uint8 intermediate subgoal images, K >= 0, in the order they are to be reached, and the planner's
diagnostics for the task's journal line; the runner appends the goal image as the last subgoal, so
every planner ends at the true goal (paper App. 10: the true goal is the final subgoal; No-subgoal = ``[goal]``, TAP =
``[TAP(start, goal), goal]``, KEYIN = ``[K^1..K^L, goal]``). The learned ones are
:mod:`keyin.planning.latent_cem` (KEYIN, Jumpy) and :mod:`keyin.planning.tap_subgoals` (TAP).
"""

from __future__ import annotations

from typing import NamedTuple, Protocol

import numpy as np

from keyin.errors import DatasetFormatError
from keyin.planning.tasks import PlanningTask


class Subgoals(NamedTuple):
    """What a high-level planner proposes for one task.

    Attributes:
        images: (K, H, W, 3) uint8 intermediate subgoals, the goal not included.
        diagnostics: numbers written into the task's ``tasks.jsonl`` line (names unique to the planner).
    """

    images: np.ndarray
    diagnostics: dict[str, float]


class SubgoalPlanner(Protocol):
    def __call__(
        self, start: np.ndarray, goal: np.ndarray, task: PlanningTask, rng: np.random.Generator
    ) -> Subgoals:
        """(H, W, 3) start and goal images -> the (K, H, W, 3) intermediate subgoals and diagnostics."""
        ...


class NoSubgoals:
    """The paper's *No subgoals* row: the goal image is the only subgoal."""

    def __call__(
        self, start: np.ndarray, goal: np.ndarray, task: PlanningTask, rng: np.random.Generator
    ) -> Subgoals:
        return Subgoals(np.empty((0, *goal.shape), goal.dtype), {})


class DemoSubgoals:
    """Oracle (not in the paper): the demonstration's own keyframes, the puck at the end of each push,
    i.e. what a perfect keyframe predictor would propose."""

    def __call__(
        self, start: np.ndarray, goal: np.ndarray, task: PlanningTask, rng: np.random.Generator
    ) -> Subgoals:
        if task.subgoal_frames is None:
            raise DatasetFormatError(
                "the planning tasks have no subgoal_frames (written by an older keyin); regenerate them "
                "with keyin-generate dataset=pushing 'splits={planning: 240}' into a new data_dir"
            )
        return Subgoals(task.subgoal_frames, {})
