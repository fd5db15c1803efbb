"""Planning metrics (paper Table 2, REFERENCE §5.2) from per-task final position errors.

The position error is the shortest path around the wall from the final puck to the goal. The paper
gives no success threshold; REFERENCE §5.2 reads about half the initial distance from its numbers,
so the threshold is a setting (world units) and the success-vs-threshold curve is reported too.
"""

from __future__ import annotations

import numpy as np


def successes(errors: np.ndarray, threshold: float) -> np.ndarray:
    """(n,) bool: the final error is within ``threshold``."""
    return np.asarray(errors, dtype=np.float64) <= threshold


def success_curve(errors: np.ndarray, thresholds: np.ndarray) -> np.ndarray:
    """(T,) success rate at each threshold (T,)."""
    errors = np.asarray(errors, dtype=np.float64)
    return (errors[None, :] <= np.asarray(thresholds, dtype=np.float64)[:, None]).mean(axis=1)


def planning_summary(errors: np.ndarray, initial: np.ndarray, threshold: float) -> dict[str, float | int]:
    """Mean and std over tasks (population, as "± std over episodes") of the final errors (n,), the
    success rate, and the mean relative error ``final / initial`` (n,)."""
    errors, initial = np.asarray(errors, dtype=np.float64), np.asarray(initial, dtype=np.float64)
    return {
        "n_tasks": int(len(errors)),
        "position_error_mean": float(errors.mean()),
        "position_error_std": float(errors.std()),
        "success_rate": float(successes(errors, threshold).mean()),
        "relative_error_mean": float((errors / initial).mean()),
        "initial_distance_mean": float(initial.mean()),
    }
