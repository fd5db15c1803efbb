"""Pictures of one planned task, like the paper's Fig. 6/8: the subgoals over the executed episode.

``<name>.png``: top row the start image, the subgoal images handed to the servo and the goal;
bottom row, under each subgoal, the executed frame at the last step that planned for it (blank
where the servo skipped it), the goal's puck shown faintly in every executed frame.
``<name>.gif``: every executed step, the frame beside the subgoal it plans for.
"""

from __future__ import annotations

from pathlib import Path

import imageio.v3 as iio
import numpy as np

GOAL_OPACITY = 0.35  # how strongly the goal image shows through the executed frames


def with_goal(frames: np.ndarray, goal: np.ndarray) -> np.ndarray:
    """(T, H, W, 3) uint8 frames with the (H, W, 3) goal image blended in where they differ."""
    differs = np.any(frames != goal, axis=-1, keepdims=True)
    blended = (1 - GOAL_OPACITY) * frames + GOAL_OPACITY * goal
    return np.where(differs, blended, frames).round().astype(np.uint8)


def last_step_per_subgoal(subgoal: np.ndarray, count: int) -> list[int | None]:
    """For each of ``count`` subgoals, the last executed step (frame index, 1 … T) that planned for
    it, or None if no step did."""
    steps: list[int | None] = [None] * count
    for step, index in enumerate(subgoal.tolist(), start=1):
        steps[index] = step
    return steps


def save_plan_pictures(
    folder: Path,
    name: str,
    start: np.ndarray,
    subgoals: np.ndarray,
    frames: np.ndarray,
    subgoal: np.ndarray,
    gap: int = 4,
) -> tuple[Path, Path]:
    """Write ``<name>.png`` and ``<name>.gif`` (module doc) into ``folder``.

    Args:
        start: (H, W, 3) uint8 start image.
        subgoals: (K, H, W, 3) uint8 subgoal images, the goal last.
        frames: (T + 1, H, W, 3) uint8 executed frames, the start first.
        subgoal: (T,) index into ``subgoals`` each step planned for.
        gap: white pixels between images.
    Returns:
        The PNG and GIF paths.
    """
    goal = subgoals[-1]
    shown = with_goal(frames, goal)
    blank = np.full_like(start, 255)
    last_steps = last_step_per_subgoal(subgoal, len(subgoals))
    executed = [shown[0]] + [blank if step is None else shown[step] for step in last_steps]
    if len(subgoal) and subgoal[-1] != len(subgoals) - 1:
        executed[-1] = shown[-1]  # the episode ended before the goal's turn: show where it ended
    rows = [np.concatenate([start[None], subgoals]), np.stack(executed)]
    height, width = start.shape[:2]
    canvas = np.full((2 * height + 3 * gap, len(rows[0]) * (width + gap) + gap, 3), 255, np.uint8)
    for r, row in enumerate(rows):
        for c, image in enumerate(row):
            top, left = gap + r * (height + gap), gap + c * (width + gap)
            canvas[top: top + height, left: left + width] = image
    target = np.append(subgoal, subgoal[-1] if len(subgoal) else len(subgoals) - 1)  # (T + 1,) beside frame t
    movie = np.concatenate([shown, np.full((len(shown), height, gap, 3), 255, np.uint8), subgoals[target]], axis=2)
    scale = max(1, 256 // height)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    png, gif = folder / f"{name}.png", folder / f"{name}.gif"
    iio.imwrite(png, canvas.repeat(2, axis=0).repeat(2, axis=1))
    iio.imwrite(gif, movie.repeat(scale, axis=1).repeat(scale, axis=2), duration=200, loop=0)
    return png, gif
