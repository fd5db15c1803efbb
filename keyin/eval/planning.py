"""Planning metrics (paper Table 2, §4.2) from per-task final position errors.

The position error is the shortest path around the wall from the final puck to the goal. The paper
gives no success threshold; docs/planning.md ("Success threshold") reads about half the initial distance from Table 2,
so the threshold is a setting (world units) and the success-vs-threshold curve is reported too.
"""

from __future__ import annotations

import numpy as np

from keyin.envs.geometry import shortest_path_length, to_wall_frame

# How a task ended (:func:`episode_outcome`), in the order they are tested.
OUTCOMES = ("success", "untouched", "reached_then_lost", "not_crossed", "crossed_missed")
# In a planning job's run dir beside tasks.jsonl: the run config stored in the checkpoint of the model it planned with
# (keyin-plan writes it; keyin-report names a row of the paper's method after that model's frame model and sizes).
MODEL_CONFIG = "model_config.yaml"
UNTOUCHED_BELOW = 0.05  # world units: a puck that never left this disc round its start was not pushed


def successes(errors: np.ndarray, threshold: float) -> np.ndarray:
    """(n,) bool: the final error is within ``threshold``."""
    return np.asarray(errors, dtype=np.float64) <= threshold


def success_curve(errors: np.ndarray, thresholds: np.ndarray) -> np.ndarray:
    """(T,) success rate at each threshold (T,)."""
    errors = np.asarray(errors, dtype=np.float64)
    return (errors[None, :] <= np.asarray(thresholds, dtype=np.float64)[:, None]).mean(axis=1)


def bootstrap_interval(
    values: np.ndarray, level: float = 0.95, resamples: int = 10_000, seed: int = 0
) -> tuple[float, float]:
    """Percentile bootstrap interval of the mean of (n,) values (tasks resampled with replacement).

    For paired values, e.g. one planner's success minus another's on the same tasks, pass the
    per-task differences: resampling tasks keeps the pairs together.
    """
    values = np.asarray(values, dtype=np.float64)
    indices = np.random.default_rng(seed).integers(0, len(values), size=(resamples, len(values)))
    means = values[indices].mean(axis=1)
    tail = (1.0 - level) / 2.0
    return float(np.quantile(means, tail)), float(np.quantile(means, 1.0 - tail))


def planning_summary(errors: np.ndarray, initial: np.ndarray, threshold: float) -> dict[str, float | int]:
    """Mean and std over tasks (population, as "± std over episodes") of the final errors (n,), the
    success rate with its 95 % bootstrap interval over tasks, and the mean relative error
    ``final / initial`` (n,)."""
    errors, initial = np.asarray(errors, dtype=np.float64), np.asarray(initial, dtype=np.float64)
    succeeded = successes(errors, threshold)
    low, high = bootstrap_interval(succeeded)
    return {
        "n_tasks": int(len(errors)),
        "position_error_mean": float(errors.mean()),
        "position_error_std": float(errors.std()),
        "success_rate": float(succeeded.mean()),
        "success_rate_low": low,
        "success_rate_high": high,
        "relative_error_mean": float((errors / initial).mean()),
        "initial_distance_mean": float(initial.mean()),
    }


def episode_outcome(
    puck: np.ndarray, wall: np.ndarray, goal: np.ndarray, inflate: float, threshold: float
) -> dict[str, float | bool | str]:
    """How an episode ended, read from the puck's path.

    Every task's goal lies across the wall from the puck's start (:mod:`keyin.envs.layout`), so a
    failure either never moved the puck (``untouched``), came within ``threshold`` of the goal and
    left it again (``reached_then_lost``), ended on the start's side of the wall's centre line
    (``not_crossed``) or crossed it and stopped away from the goal (``crossed_missed``).

    Args:
        puck: (T + 1, 2) world positions of the puck, the start first.
        wall: (5,) the task's wall; goal: (2,) its goal.
        inflate: the puck radius (the error is the shortest path round the inflated wall).
        threshold: the success threshold (world units).
    Returns:
        ``outcome`` (one of :data:`OUTCOMES`), ``closest_error`` (the smallest error along the
        episode), ``puck_moved`` (farthest distance of the puck from its start) and ``crossed_wall``.
    """
    puck = np.asarray(puck, dtype=np.float64)
    errors = np.array([shortest_path_length(point, goal, wall, inflate) for point in puck])
    moved = float(np.linalg.norm(puck - puck[0], axis=1).max())
    start_side, final_side = np.sign(to_wall_frame(puck[[0, -1]], wall)[:, 1])
    crossed = bool(start_side != final_side)
    if errors[-1] <= threshold:
        outcome = "success"
    elif moved < UNTOUCHED_BELOW:
        outcome = "untouched"
    elif errors.min() <= threshold:
        outcome = "reached_then_lost"
    else:
        outcome = "crossed_missed" if crossed else "not_crossed"
    return {"outcome": outcome, "closest_error": float(errors.min()), "puck_moved": moved, "crossed_wall": crossed}
