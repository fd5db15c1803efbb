"""Which subgoals a planning job's servo could see, against how its tasks ended.

    python studies/planning_subgoals.py docs/results/pushing_table2/jobs/keyin_paper_seed1 \
        --out studies/results/planning_subgoals_keyin_paper_seed1.md

For each task the job played, its high-level planner is run again from the job's config (the
committed checkpoint) with the task's own randomness (``default_rng([seed, task])``, drawn before the
servo's), so the subgoals are the ones of the episode: the replayed diagnostics (``plan_cost_px``,
``plan_samples_without_puck``) must equal the recorded ones, or the script stops. A subgoal whose puck
colour segmentation finds nothing is skipped by the servo (keyin/planning/servo.py); the table
gives the success rate by how many of the K subgoals showed a puck. Nothing is simulated.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections import Counter
from datetime import date
from pathlib import Path

import numpy as np
import torch
from hydra.utils import instantiate
from omegaconf import OmegaConf

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # common.py stays with the benchmarks
from common import cpu_model, publish  # noqa: E402
from keyin.data.hdf5 import split_files  # noqa: E402
from keyin.data.pushing import PLANNING_SPLIT  # noqa: E402
from keyin.planning.servo import subgoal_pixels  # noqa: E402
from keyin.planning.tasks import read_tasks  # noqa: E402


def visible_subgoals(job: Path, data_dir: str, limit: int | None) -> list[dict]:
    """Per recorded task of ``job``: its outcome and how many of its subgoals show a puck."""
    cfg = OmegaConf.load(job / "config.yaml")
    records = {r["task"]: r for r in map(json.loads, (job / "tasks.jsonl").read_text().splitlines())}
    planner = instantiate(cfg.planner.controller).subgoals
    tasks, _ = read_tasks(split_files(Path(data_dir) / cfg.dataset.name, PLANNING_SPLIT))
    rows = []
    for task in [task for task in tasks if task.index in records][:limit]:
        record = records[task.index]
        planned = planner(task.start_image, task.goal_image, task, np.random.default_rng([cfg.seed, task.index]))
        for key, value in planned.diagnostics.items():
            if not np.isclose(value, record[key], rtol=1e-9, atol=0):
                raise SystemExit(f"task {task.index}: replayed {key} {value} differs from the recorded {record[key]}; "
                                 "the subgoals are not the episode's (another checkpoint, code or data?)")
        shown = ~np.isnan(subgoal_pixels(planned.images)).any(axis=-1)
        rows.append({"task": task.index, "success": record["success"], "outcome": record["outcome"],
                     "visible": int(shown.sum()), "subgoals": len(shown), "subgoals_used": record["subgoals_used"]})
    return rows


def report(job: Path, rows: list[dict], seconds: float, command: str) -> str:
    counts = Counter(row["visible"] for row in rows)
    lines = [
        f"## Subgoals the servo could see: {job}",
        "",
        f"- command: `{command}`",
        f"- machine: {cpu_model()}, torch {torch.__version__}, one thread, {date.today()}; {seconds:.0f} s for "
        f"{len(rows)} tasks; every replayed diagnostic equals the recorded one",
        f"- success: {np.mean([r['success'] for r in rows]):.3f}; subgoals with a puck, mean: successes "
        f"{np.mean([r['visible'] for r in rows if r['success']] or [np.nan]):.2f}, failures "
        f"{np.mean([r['visible'] for r in rows if not r['success']] or [np.nan]):.2f} (of {rows[0]['subgoals']})",
        "",
        "| subgoals with a puck | tasks | success | outcomes |",
        "|---|---|---|---|",
    ]
    for visible in sorted(counts):
        group = [r for r in rows if r["visible"] == visible]
        outcomes = ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in sorted(Counter(r["outcome"] for r in group).items()))
        lines.append(f"| {visible} | {len(group)} | {np.mean([r['success'] for r in group]):.3f} | {outcomes} |")
    return "\n".join(lines) + "\n"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("job", type=Path, help="a planning job folder: config.yaml and tasks.jsonl")
    parser.add_argument("--tasks", type=int, help="the first n of its tasks (default all)")
    parser.add_argument("--data-dir", default="data")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    torch.set_num_threads(1)
    started = time.perf_counter()
    rows = visible_subgoals(args.job, args.data_dir, args.tasks)
    command = f"python studies/planning_subgoals.py {args.job}" + (f" --tasks {args.tasks}" if args.tasks else "")
    publish(report(args.job, rows, time.perf_counter() - started, command), args.out)


if __name__ == "__main__":
    main()
