"""The paper's Table 2 from a ``keyin-plan`` sweep: every job's tasks, pooled per planner, formatted.

A job is a run dir with ``metrics.json`` (``planner``, ``seed``, ``n_tasks``, ``success_threshold``)
and ``tasks.jsonl`` (one final position error per task). A row is one planner: the mean ± std over
all its tasks (of every seed; the paper's ± is over episodes), the success rate at one threshold,
and the paper's numbers beside ours.
"""

from __future__ import annotations

import csv
import io
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from omegaconf import DictConfig, OmegaConf
from omegaconf.errors import OmegaConfBaseException

from keyin.eval.planning import MODEL_CONFIG, OUTCOMES, bootstrap_interval, planning_summary, success_curve
from keyin.eval.report import (
    PAPER_METHOD, Roots, group_by_seed, is_planning, method_of, model_run, named_as_run, read_metrics,
)
from keyin.io import read_json_lines

# Paper Table 2 (paper §4.2): position error mean, std and success rate in % (None: "-"). A learned
# row is named after the model it plans with; the paper's KEYIN stands beside keyin_paper (its method)
# and beside keyin_plus (ours).
PAPER_TABLE2 = {
    "initial": (1.32, 0.06, None),
    "random": (1.32, 0.07, None),
    "no_subgoals": (0.90, 0.14, 15.0),
    "tap": (0.80, 0.16, 23.3),
    "surprise": (0.64, 0.28, 50.8),
    "jumpy": (0.62, 0.33, 58.8),
    "keyin_paper": (0.50, 0.26, 64.2),
    "keyin_plus": (0.50, 0.26, 64.2),
}
PLANNER_ORDER = (*PAPER_TABLE2, "demo_subgoals")
# The servo settings a job records in its metrics.json (keyin-plan since 0.2), with the defaults a job
# that records none ran with; a row of another setting is named after it (``jumpy · pixels · env steps``).
SERVO_DEFAULTS = {"servo_observe": "state", "servo_action_repeat": 2, "servo_horizon": 8}
CURVE_END = 1.6  # world units: the success curves reach at least this threshold (past the initial distances)
NOT_RECORDED = "not recorded"
MODEL_NOT_RECORDED = "model not recorded"  # a row of the paper's method whose jobs hold no model config (planned before 2026-12-07)


@dataclass
class PlanningRow:
    """One planner in one servo setting over all its tasks.

    Attributes:
        planner: the row's name: ``base``, followed by its ``setting`` unless the default.
        base: the planner's name (``metrics.json``'s ``planner``), followed by what its model changed of the paper's
            stated choices where it is the paper's method (:func:`named_planner`).
        setting: :func:`servo_setting` of its jobs.
        model_seed: the one model seed its jobs planned with under their own planning seeds, or
            None where each seed planned with its own model (:func:`fixed_model_seed`).
        tasks: (seed, task index) of each of its n tasks, in the order of ``errors``.
        errors, initial: (n,) final and initial shortest-path distances of its tasks.
        summary: :func:`keyin.eval.planning.planning_summary` of them.
        seed_success: each seed's success rate, in ``seeds`` order (its spread is the model seeds',
            with the CEM's; the planning seeds' alone where ``model_seed`` is set).
        seconds_per_task: the tasks' mean wall time in one worker process (one core each).
        machines: each seed's :func:`machine_name` (what its wall times were measured on).
        paper: the paper's (error mean, error std, success %) or None.
        outcomes: how many of its tasks ended in each :data:`keyin.eval.planning.OUTCOMES` (servo
            episodes of a keyin-plan that records them), ``not recorded`` for the others.
    """

    planner: str
    base: str
    setting: str
    model_seed: int | None
    seeds: list[int]
    tasks: list[tuple[int, int]]
    errors: np.ndarray
    initial: np.ndarray
    steps_mean: float
    summary: dict[str, float | int]
    seed_success: list[float]
    seconds_per_task: float
    machines: dict[int, str]
    paper: tuple[float, float, float | None] | None
    outcomes: dict[str, int]


def named_planner(planner: str, model_config: DictConfig | None) -> str:
    """A planner's name in the table: one of the paper's method (``keyin_paper``) names what the model it planned with
    changed of the paper's stated choices, as Table 1 names that model's row (:func:`keyin.eval.report.named_as_run`:
    ``keyin_paper · backbone=ours scale=cpu``), from the model's run config (``model_config``, the job's
    :data:`~keyin.eval.planning.MODEL_CONFIG`), or says it is not recorded (None). Others keep their name."""
    if not planner.startswith(PAPER_METHOD):
        return planner
    if model_config is None:
        return f"{planner} · {MODEL_NOT_RECORDED}"
    return named_as_run(planner, model_run(model_config), model_config)


def read_model_config(folder: Path) -> DictConfig | None:
    """A planning job's :data:`~keyin.eval.planning.MODEL_CONFIG`, None where it has none.

    Raises:
        ValueError: a file that is not a YAML mapping of a run config.
    """
    path = folder / MODEL_CONFIG
    if not path.is_file():
        return None
    try:
        config = OmegaConf.load(path)
    except (yaml.YAMLError, OmegaConfBaseException) as err:
        raise ValueError(f"{path} is not YAML ({type(err).__name__}); plan the job again to rewrite it") from None
    if not isinstance(config, DictConfig) or "model" not in config:
        raise ValueError(f"{path} holds no run config (no `model` entry); plan the job again to rewrite it")
    return config


def collect_planning(root: Roots) -> list[dict[str, Any]]:
    """Every planning job under ``root`` (one sweep folder or several): its metrics plus ``tasks``, the records of the ``n_tasks``
    tasks it reported (the first ones of the split), ``named`` (:func:`named_planner`) and ``path``.

    Raises:
        ValueError: a job whose tasks.jsonl holds fewer tasks than its metrics.json counts.
    """
    jobs = []
    for folder, metrics in read_metrics(root):
        if not is_planning(metrics):
            continue
        records = sorted(read_json_lines(folder / "tasks.jsonl")[0], key=lambda record: record["task"])
        tasks = records[: metrics["n_tasks"]]
        if len(tasks) < metrics["n_tasks"]:
            raise ValueError(
                f"{folder / 'tasks.jsonl'} holds {len(tasks)} tasks but its metrics.json counts "
                f"{metrics['n_tasks']}; run the job again to rebuild it"
            )
        named = named_planner(metrics["planner"], read_model_config(folder))
        jobs.append({**metrics, "seed": metrics.get("seed", 0), "tasks": tasks, "named": named, "path": str(folder)})
    return jobs


def sweep_threshold(jobs: list[dict[str, Any]]) -> float:
    """The success threshold all jobs used.

    Raises:
        ValueError: if they used different ones.
    """
    thresholds = sorted({float(job["success_threshold"]) for job in jobs})
    if len(thresholds) != 1:
        raise ValueError(f"the jobs used different success thresholds {thresholds}; choose one with --threshold")
    return thresholds[0]


def planner_sort_key(planner: str) -> tuple[int, str]:
    """Table order: the paper's rows, then the oracle, then anything else (by the planner a row name starts with)."""
    method = method_of(planner)
    return (PLANNER_ORDER.index(method) if method in PLANNER_ORDER else len(PLANNER_ORDER), planner)


def servo_setting(job: dict[str, Any]) -> str:
    """How a job's servo observed, counted time and planned: ``state · servo steps`` (the default),
    ``pixels · env steps`` (colour segmentation, one action per environment step), ``state · servo
    steps · plans of 16 actions`` (a longer plan than the paper's l = 8), ..."""
    observe = job.get("servo_observe", SERVO_DEFAULTS["servo_observe"])
    repeat = int(job.get("servo_action_repeat", SERVO_DEFAULTS["servo_action_repeat"]))
    horizon = int(job.get("servo_horizon", SERVO_DEFAULTS["servo_horizon"]))
    unit = {1: "env steps", 2: "servo steps"}.get(repeat, f"{repeat} env steps per servo step")
    plans = "" if horizon == SERVO_DEFAULTS["servo_horizon"] else f" · plans of {horizon} actions"
    return f"{observe} · {unit}{plans}"


DEFAULT_SETTING = servo_setting({})


def machine_name(job: dict[str, Any]) -> str:
    """A job's machine as one phrase (``Intel(R) Xeon(R) Processor, 2 CPUs, torch 2.13.0+cpu``),
    :data:`NOT_RECORDED` for a job whose metrics.json has none (written before keyin recorded it)."""
    machine = job.get("machine")
    if not machine:
        return NOT_RECORDED
    gpu = f", {machine['gpu']}" if machine.get("gpu") else ""
    return f"{machine['cpu']}, {machine['cpus']} CPUs, torch {machine['torch']}{gpu}"


def fixed_model_seed(job: dict[str, Any]) -> int | None:
    """The model seed of a job that planned with another model seed than its planning seed (one
    model under several planning seeds: the CEM's share of the spread over seeds), else None."""
    model_seed = job.get("model_seed")
    return None if model_seed is None or model_seed == job["seed"] else int(model_seed)


def row_name(planner: str, setting: str, model_seed: int | None = None) -> str:
    name = planner if setting == DEFAULT_SETTING else f"{planner} · {setting}"
    return name if model_seed is None else f"{name} · model seed {model_seed}"


def row_order(key: tuple[str, str, int | None]) -> tuple:
    """Table order of a (planner, setting, model seed) row: the default setting first, then the
    other servo settings, then one model under other planning seeds; within each, :func:`planner_sort_key`."""
    planner, setting, model_seed = key
    return (model_seed is not None, setting != DEFAULT_SETTING, setting, *planner_sort_key(planner), model_seed or 0)


def summarise_planning(jobs: list[dict[str, Any]], threshold: float) -> list[PlanningRow]:
    """One row per planner and servo setting, its tasks of every seed pooled; the jobs that planned
    one model under other planning seeds (:func:`fixed_model_seed`) are a row of their own.

    Raises:
        ValueError: if a (planner, setting, seed) appears twice (two sweeps under one root).
    """
    def key_of(job: dict[str, Any]) -> tuple[str, str, int | None]:
        return job["named"], servo_setting(job), fixed_model_seed(job)

    groups = group_by_seed(jobs, key_of, lambda job: f"planner {row_name(*key_of(job))}")
    rows = []
    for key in sorted(groups, key=row_order):
        planner, setting, model_seed = key
        tasks = [task for job in groups[key].values() for task in job["tasks"]]
        keys = [(seed, task["task"]) for seed, job in groups[key].items() for task in job["tasks"]]
        errors = np.array([task["final_error"] for task in tasks], dtype=np.float64)
        initial = np.array([task["initial_distance"] for task in tasks], dtype=np.float64)
        rows.append(
            PlanningRow(
                planner=row_name(planner, setting, model_seed),
                base=planner,
                setting=setting,
                model_seed=model_seed,
                seeds=sorted(groups[key]),
                tasks=keys,
                errors=errors,
                initial=initial,
                steps_mean=float(np.mean([task["steps"] for task in tasks])),
                summary=planning_summary(errors, initial, threshold),
                seed_success=[
                    float(np.mean([task["final_error"] <= threshold for task in groups[key][seed]["tasks"]]))
                    for seed in sorted(groups[key])
                ],
                seconds_per_task=float(np.mean([task["seconds"] for task in tasks])),
                machines={seed: machine_name(job) for seed, job in sorted(groups[key].items())},
                paper=PAPER_TABLE2.get(method_of(planner)),
                outcomes=dict(Counter(task.get("outcome", NOT_RECORDED) for task in tasks)),
            )
        )
    return rows


def success_curves(rows: list[PlanningRow], points: int = 321) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Each planner's success rate against the success threshold (``table2_success.png``).

    Returns:
        (T,) thresholds from 0 to past the largest final error (at least ``CURVE_END``), and
        ``"<planner> (<n> tasks)"`` → (T,) its success rate at each of them.
    """
    top = max(CURVE_END, max(float(row.errors.max()) for row in rows) + 0.05)
    thresholds = np.linspace(0.0, top, points)
    curves = {f"{row.planner} ({len(row.errors)} tasks)": success_curve(row.errors, thresholds) for row in rows}
    return thresholds, curves


def paired_success_difference(first: PlanningRow, second: PlanningRow, threshold: float) -> dict[str, float | int]:
    """``first``'s success rate minus ``second``'s on the tasks (seed, task) both played, with its
    95 % paired bootstrap interval over those tasks."""
    second_errors = dict(zip(second.tasks, second.errors))
    common = [(key, error) for key, error in zip(first.tasks, first.errors) if key in second_errors]
    if not common:
        raise ValueError(f"{first.planner} and {second.planner} share no task")
    differences = np.array(
        [float(error <= threshold) - float(second_errors[key] <= threshold) for key, error in common]
    )
    low, high = bootstrap_interval(differences)
    return {"difference": float(differences.mean()), "low": low, "high": high, "n_tasks": len(common)}


DIFFERENCE_PAIRS = (
    ("keyin_paper", "jumpy"), ("keyin_plus", "jumpy"), ("keyin_plus", "keyin_paper"),
    ("surprise", "jumpy"), ("keyin_paper", "surprise"), ("tap", "no_subgoals"),  # the baselines' order (issue 45)
)


def difference_markdown(rows: list[PlanningRow], threshold: float, pairs: tuple[tuple[str, str], ...] = DIFFERENCE_PAIRS) -> str:
    """One line per pair of planners (KEYIN − Jumpy, ours − the paper's, the baselines' order) that are both in ``rows``
    in the default servo setting, each model seed its own (a row named after what its model changed stands for its
    planner, :func:`named_planner`; two rows that share no task are not paired): the success difference in points
    with its paired interval; empty if none is."""
    by_planner: dict[str, list[PlanningRow]] = {}
    for row in rows:
        if row.setting == DEFAULT_SETTING and row.model_seed is None:
            by_planner.setdefault(method_of(row.base), []).append(row)
    lines = []
    for first, second in pairs:
        for one in by_planner.get(first, []):
            for other in by_planner.get(second, []):
                if not set(one.tasks) & set(other.tasks):
                    continue
                d = paired_success_difference(one, other, threshold)
                lines.append(
                    f"- {one.planner} − {other.planner} success: {100 * d['difference']:+.1f} points, 95 % paired "
                    f"bootstrap interval [{100 * d['low']:+.1f}, {100 * d['high']:+.1f}] over {d['n_tasks']} common tasks"
                )
    return "\n".join(lines) + ("\n" if lines else "")


def seed_spread(row: PlanningRow) -> str:
    """The success rate's mean ± std over the row's seeds (sample std), ``–`` for one seed."""
    if len(row.seed_success) < 2:
        return "–"
    rates = 100 * np.array(row.seed_success)
    return f"{rates.mean():.1f} ± {rates.std(ddof=1):.1f} %"


def planning_markdown(rows: list[PlanningRow], threshold: float) -> str:
    """Table 2 as Markdown: position error mean ± std and success rate (with its 95 % bootstrap
    interval over tasks, and its spread over seeds), ours beside the paper's."""
    lines = [
        f"| planner | position error (ours) | position error (paper) | success ≤ {threshold:g} (ours) [95 % interval] | "
        f"mean ± std over seeds | success (paper) | final / initial | steps | s / task | tasks | seeds |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in rows:
        s = row.summary
        paper_error = "–" if row.paper is None else f"{row.paper[0]:.2f} ± {row.paper[1]:.2f}"
        paper_success = "–" if row.paper is None or row.paper[2] is None else f"{row.paper[2]:.1f} %"
        lines.append(
            f"| {row.planner} | {s['position_error_mean']:.2f} ± {s['position_error_std']:.2f} | {paper_error} | "
            f"{100 * s['success_rate']:.1f} % [{100 * s['success_rate_low']:.1f}, {100 * s['success_rate_high']:.1f}] | "
            f"{seed_spread(row)} | {paper_success} | {s['relative_error_mean']:.2f} | "
            f"{row.steps_mean:.1f} | {row.seconds_per_task:.1f} | {s['n_tasks']} | {' '.join(map(str, row.seeds))} |"
        )
    return "\n".join(lines) + "\n"


def machines_markdown(rows: list[PlanningRow]) -> str:
    """Where each row's ``s / task`` was measured: one line per machine, naming its rows and seeds."""
    seeds_on: dict[str, dict[str, list[int]]] = {}
    for row in rows:
        for seed, name in row.machines.items():
            seeds_on.setdefault(name, {}).setdefault(row.planner, []).append(seed)
    lines = [
        ("- s / task of jobs that did not record their machine: " if name == NOT_RECORDED else f"- s / task on {name}: ")
        + ", ".join(f"{planner} (seeds {' '.join(map(str, seeds))})" for planner, seeds in by_row.items())
        for name, by_row in sorted(seeds_on.items(), key=lambda item: (item[0] == NOT_RECORDED, item[0]))
    ]
    return "\n".join(lines) + "\n"


def sensitivity_markdown(rows: list[PlanningRow], threshold: float) -> str:
    """Each planner planned in several servo settings: its success rate in each, with its 95 %
    bootstrap interval, on the tasks (seed, task) it played in all of them; empty if none was."""
    settings: dict[str, list[PlanningRow]] = {}
    for row in rows:
        if row.model_seed is None:
            settings.setdefault(row.base, []).append(row)
    settings = {base: group for base, group in settings.items() if len(group) > 1}
    if not settings:
        return ""
    columns = sorted({row.setting for group in settings.values() for row in group}, key=lambda s: (s != DEFAULT_SETTING, s))
    lines = [f"| planner | " + " | ".join(columns) + " | common tasks |", "|---" * (len(columns) + 2) + "|"]
    for base, group in settings.items():
        common = set.intersection(*(set(row.tasks) for row in group))
        cells = {}
        for row in group:
            successes = np.array([error <= threshold for key, error in zip(row.tasks, row.errors) if key in common], dtype=float)
            low, high = bootstrap_interval(successes)
            cells[row.setting] = f"{100 * successes.mean():.1f} % [{100 * low:.1f}, {100 * high:.1f}]" if common else "–"
        lines.append(f"| {base} | " + " | ".join(cells.get(column, "–") for column in columns) + f" | {len(common)} |")
    return "\n".join(lines) + "\n"


def outcome_markdown(rows: list[PlanningRow]) -> str:
    """How each servo planner's tasks ended (:func:`keyin.eval.planning.episode_outcome`, at the
    runs' own threshold); empty when no row recorded it."""
    rows = [row for row in rows if set(row.outcomes) - {NOT_RECORDED}]
    if not rows:
        return ""
    columns = [*OUTCOMES, NOT_RECORDED]
    lines = ["| planner | " + " | ".join(c.replace("_", " ") for c in columns) + " |",
             "|---" * (len(columns) + 1) + "|"]
    lines += [f"| {row.planner} | " + " | ".join(str(row.outcomes.get(c, 0)) for c in columns) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def planning_csv(rows: list[PlanningRow], threshold: float) -> str:
    """The same table as CSV (success rate as a fraction; the paper's in %)."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    stats = ("position_error_mean", "position_error_std", "success_rate", "success_rate_low", "success_rate_high",
             "relative_error_mean",
             "initial_distance_mean")
    writer.writerow(["planner", "seeds", "n_tasks", "success_threshold", *stats, "seed_success_rates", "steps_mean",
                     "seconds_per_task", "paper_error_mean", "paper_error_std", "paper_success_percent"])
    for row in rows:
        paper = row.paper or (None, None, None)
        writer.writerow(
            [row.planner, " ".join(map(str, row.seeds)), row.summary["n_tasks"], f"{threshold:g}"]
            + [f"{row.summary[stat]:.6g}" for stat in stats]
            + [" ".join(f"{rate:.6g}" for rate in row.seed_success), f"{row.steps_mean:.6g}", f"{row.seconds_per_task:.6g}"]
            + ["" if value is None else value for value in paper]
        )
    return out.getvalue()
