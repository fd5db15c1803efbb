"""Play many planning tasks with one controller: in this process or in spawn workers, resumable
through the run dir's ``tasks.jsonl`` (:mod:`keyin.planning.journal`), with a progress bar.

Task ``i`` draws its randomness from ``default_rng([seed, i])``, so a task's result does not
depend on the worker count or on which run finished it. Only this process writes the journal, a
line per task as soon as it is finished (workers return their records).
"""

from __future__ import annotations

import multiprocessing
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Sequence

import numpy as np
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from keyin.data.pushing import PushingGenerator
from keyin.eval.planning import episode_outcome, successes
from keyin.envs.layout import Layout
from keyin.io import append_json_line
from keyin.planning.controllers import Controller, Outcome
from keyin.planning.journal import read_journal
from keyin.planning.servo import ServoParams
from keyin.planning.tasks import PlanningTask, start_task
from keyin.viz.planning import save_plan_pictures
from keyin.workers import exit_with_parent


@dataclass(frozen=True)
class PlanJob:
    """Everything a worker needs besides the task (plain picklable objects)."""

    planner: str
    controller: Controller
    servo: ServoParams
    generator: PushingGenerator  # its environment reproduces the tasks' scene
    seed: int
    threshold: float
    pictures: frozenset[int] = frozenset()  # the indices of the tasks that get pictures of their episode ...
    picture_dir: Path | None = None  # ... in this folder (keyin.viz.planning)
    outcome_pictures: bool = False  # and the first task of each outcome kind: outcome_<kind>_task<i>.png|gif


def play(job: PlanJob, task: PlanningTask) -> dict[str, Any]:
    """Play one task; its journal record."""
    env = job.generator.environment()
    start = time.perf_counter()
    start_task(env, task)
    outcome = job.controller.run(env, task, job.servo, np.random.default_rng([job.seed, task.index]))
    seconds = time.perf_counter() - start
    how = {}
    if outcome.trajectory is not None:
        layout = Layout.from_array(task.layout)
        how = episode_outcome(
            outcome.trajectory.puck, layout.wall, layout.goal, env.task.scene.puck_radius, job.threshold
        )
        if job.picture_dir is not None:
            draw_episode(job, task, outcome, picture_names(job, task, how["outcome"]))
    return {
        "task": task.index,
        "planner": job.planner,
        "seed": job.seed,
        "final_error": outcome.final_error,
        "initial_distance": task.initial_distance,
        "success": bool(successes(np.array([outcome.final_error]), job.threshold)[0]),
        "steps": outcome.steps,
        "subgoals": outcome.subgoals,
        "subgoals_used": outcome.subgoals_used,
        "seconds": seconds,
        **how,
        **outcome.diagnostics,
    }


def picture_names(job: PlanJob, task: PlanningTask, kind: str) -> list[str]:
    """The names an episode's pictures get: ``task<i>`` where its index was asked for, and
    ``outcome_<kind>_task<i>`` where no episode of its outcome kind has a picture in the folder yet
    (workers check the folder, so two kinds finishing at once may both be drawn: at least one each)."""
    names = [f"task{task.index:03d}"] if task.index in job.pictures else []
    if job.outcome_pictures and not any(job.picture_dir.glob(f"outcome_{kind}_task*.png")):
        names.append(f"outcome_{kind}_task{task.index:03d}")
    return names


def draw_episode(job: PlanJob, task: PlanningTask, outcome: Outcome, names: Sequence[str]) -> None:
    """``<name>.png|gif`` for every name: the subgoals over the executed episode (:mod:`keyin.viz.planning`)."""
    if not names:
        return
    trajectory = outcome.trajectory
    wall = Layout.from_array(task.layout).wall
    frames = job.generator.render_positions(wall, trajectory.puck, trajectory.pusher)
    for name in names:
        save_plan_pictures(job.picture_dir, name, task.start_image, outcome.images, frames, trajectory.subgoal)


def run_tasks(
    job: PlanJob, tasks: Sequence[PlanningTask], journal: Path, workers: int = 1, progress: bool = True
) -> tuple[list[dict[str, Any]], dict[str, int]]:
    """Play every task the journal does not hold yet.

    Returns:
        the records of ``tasks`` in their order; counts of tasks ``skipped`` (finished earlier),
        ``played`` now and ``partial_lines_dropped`` (0 or 1, a killed run's last line).
    """
    earlier, dropped = read_journal(journal)
    wanted = {task.index for task in tasks}
    records = {record["task"]: record for record in earlier if record.get("task") in wanted}
    todo = [task for task in tasks if task.index not in records]
    columns = (
        TextColumn("[bold]{task.description}"),
        BarColumn(),
        TextColumn("{task.completed}/{task.total} tasks"),
        TextColumn("success {task.fields[success]:.0%}, error {task.fields[error]:.2f}"),
        TimeElapsedColumn(),
        TimeRemainingColumn(),
    )

    def stats() -> dict[str, float]:
        errors = np.array([record["final_error"] for record in records.values()])
        if not len(errors):
            return {"success": 0.0, "error": float("nan")}
        return {"success": float(successes(errors, job.threshold).mean()), "error": float(errors.mean())}

    with Progress(*columns, disable=not progress) as bar:
        handle = bar.add_task(f"{job.planner} -> {journal}", total=len(tasks), completed=len(records), **stats())

        def finished(record: dict[str, Any]) -> None:
            append_json_line(journal, record)
            records[record["task"]] = record
            bar.update(handle, advance=1, **stats())

        if workers <= 1 or len(todo) <= 1:
            for task in todo:
                finished(play(job, task))
        else:
            # spawn: MuJoCo with EGL can hang in a forked child (docs/pushing.md).
            context = multiprocessing.get_context("spawn")
            pool = ProcessPoolExecutor(
                min(workers, len(todo)), mp_context=context, initializer=exit_with_parent, initargs=(os.getpid(),)
            )
            try:
                for future in as_completed([pool.submit(play, job, task) for task in todo]):
                    finished(future.result())
            finally:  # on an error, do not wait for the tasks not started yet
                pool.shutdown(cancel_futures=True)
    counts = {"skipped": len(tasks) - len(todo), "played": len(todo), "partial_lines_dropped": int(dropped)}
    return [records[task.index] for task in tasks], counts
