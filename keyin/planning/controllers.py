"""What ``keyin-plan`` runs on a task: one row of the paper's Table 2 (paper §4.2, App. 10).

A controller plays one task from its start state in the pixel-free environment and reports an
:class:`Outcome`. Every controller gets the same low-level settings (``ServoParams``: the paper
uses "the same low-level planner" for all methods, so only the subgoals differ):

* :class:`Hierarchical`: a high-level planner (:mod:`keyin.planning.subgoals`) proposes subgoal
  images, the goal image is appended, and the CEM servo (:func:`run_servo`) works through them;
* :class:`StayPut` (*Initial*): no motion, the error is the start's distance to the goal;
* :class:`RandomActions` (*Random*): uniform random actions in ``[-a_max, a_max]²`` for
  ``max_timesteps`` servo steps (each held ``action_repeat`` environment steps), no planning.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from keyin.planning.servo import ServoParams, ServoTrajectory, execute, run_servo, subgoal_pixels
from keyin.planning.subgoals import SubgoalPlanner
from keyin.planning.tasks import PlanningTask


@dataclass(frozen=True)
class Outcome:
    """One task's result.

    Attributes:
        final_error: shortest path around the wall from the final puck to the goal (paper §4.2).
        steps: servo steps executed.
        subgoals: subgoal images handed to the servo, the goal included (0 without a servo).
        subgoals_used: distinct subgoals the servo planned for.
        diagnostics: the high-level planner's (:class:`keyin.planning.subgoals.Subgoals`).
        images: (K, H, W, 3) uint8 subgoal images handed to the servo, the goal last; None
            without a servo.
        trajectory: the servo's episode; None without a servo.
    """

    final_error: float
    steps: int
    subgoals: int = 0
    subgoals_used: int = 0
    diagnostics: dict[str, float] = field(default_factory=dict)
    images: np.ndarray | None = None
    trajectory: ServoTrajectory | None = None


class Controller(Protocol):
    def run(self, env: Any, task: PlanningTask, servo: ServoParams, rng: np.random.Generator) -> Outcome:
        """Play ``task`` in ``env``, which :func:`keyin.planning.tasks.start_task` has reset to it."""
        ...


@dataclass(frozen=True)
class Hierarchical:
    """Subgoals from a high-level planner, then the servo through them and the goal."""

    subgoals: SubgoalPlanner

    def run(self, env: Any, task: PlanningTask, servo: ServoParams, rng: np.random.Generator) -> Outcome:
        planned = self.subgoals(task.start_image, task.goal_image, task, rng)
        images = np.concatenate([planned.images, task.goal_image[None]])
        result = run_servo(env, subgoal_pixels(images), servo, rng)
        return Outcome(
            result.final_error, len(result.subgoal), len(images), len(np.unique(result.subgoal)), planned.diagnostics,
            images, result,
        )


class StayPut:
    """*Initial*: nothing moves."""

    def run(self, env: Any, task: PlanningTask, servo: ServoParams, rng: np.random.Generator) -> Outcome:
        return Outcome(env.task.goal_distance(env.physics), steps=0)


class RandomActions:
    """*Random*: uniform random actions, no planning."""

    def run(self, env: Any, task: PlanningTask, servo: ServoParams, rng: np.random.Generator) -> Outcome:
        steps = 0
        for action in rng.uniform(-servo.max_action, servo.max_action, (servo.max_timesteps, 2)):
            steps += 1
            if execute(env, action, servo.action_repeat):
                break
        return Outcome(env.task.goal_distance(env.physics), steps)
