"""Why the servo alone (No subgoals, Table 2) fails: each planning task's geometry beside its outcome.

    python studies/no_subgoals_geometry.py docs/results/pushing_table2/jobs/no_subgoals_seed0 \
        --tasks data/pushing/planning-00000.h5 --out studies/results/no_subgoals_geometry.md

For every task: whether the straight line from the puck's start to the goal meets the wall, how far
along the wall from its end it meets it, and the shortest path around the wall over the straight
distance (the detour the servo's final-step cost must accept). Success and outcome per band of the
detour ratio show whether some geometry lets the greedy servo through.
"""

from __future__ import annotations

import argparse
import collections
import json
import sys
from datetime import date
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # common.py stays with the benchmarks
from common import cpu_model, publish  # noqa: E402
from keyin.envs.geometry import to_wall_frame  # noqa: E402
from keyin.planning.tasks import read_tasks  # noqa: E402

BANDS = [(1.0, 1.4), (1.4, 1.5), (1.5, 1.6), (1.6, 10.0)]


def straight_line_hit(layout: np.ndarray) -> tuple[bool, float]:
    """Whether start -> goal crosses the wall's centre line within the wall, and the distance from
    that crossing to the wall's nearer end (negative: the line passes beyond the end)."""
    wall, start, goal = layout[:5], layout[5:7], layout[7:9]
    (s_along, s_normal), (g_along, g_normal) = to_wall_frame(np.stack([start, goal]), wall)
    if s_normal * g_normal > 0:
        return False, float("nan")
    along = s_along + s_normal / (s_normal - g_normal) * (g_along - s_along)
    margin = float(wall[2] - abs(along))
    return margin > 0, margin


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("job", type=Path, help="a keyin-plan job folder (its tasks.jsonl)")
    parser.add_argument("--tasks", type=Path, default=Path("data/pushing/planning-00000.h5"))
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    tasks, _ = read_tasks([args.tasks])
    played = {row["task"]: row for row in map(json.loads, (args.job / "tasks.jsonl").read_text().splitlines())}
    rows = []
    for task in tasks:
        if task.index not in played:
            continue
        hit, margin = straight_line_hit(task.layout)
        straight = float(np.linalg.norm(task.layout[7:9] - task.layout[5:7]))
        rows.append((task.initial_distance / straight, hit, margin, played[task.index]))
    success = np.array([r[3]["success"] for r in rows])
    ratio, margin = np.array([r[0] for r in rows]), np.array([r[2] for r in rows])

    def spread(values: np.ndarray) -> str:
        return "none" if not len(values) else f"{np.median(values):.2f} (median), {values.min():.2f}-{values.max():.2f}"

    lines = [
        f"## No subgoals against the tasks' geometry ({args.job.name}, {len(rows)} tasks)\n",
        f"- command: `python studies/no_subgoals_geometry.py {args.job} --tasks {args.tasks}`",
        f"- machine: {cpu_model()}, {date.today()} (no planning is run: the job's tasks.jsonl is read)",
        f"- the straight line from start to goal meets the wall in **{sum(r[1] for r in rows)} of {len(rows)}** tasks, "
        f"{float(np.nanmin(margin)):.2f}-{float(np.nanmax(margin)):.2f} units from the wall's nearer end "
        f"(successes: {spread(margin[success])}; failures: {spread(margin[~success])})\n",
        "| path around the wall / straight distance | tasks | successes | outcomes |",
        "|---|---|---|---|",
    ]
    for low, high in BANDS:
        band = [r for r in rows if low <= r[0] < high]
        outcomes = collections.Counter(r[3]["outcome"] for r in band)
        lines.append(f"| {low:.1f}-{high:.1f} | {len(band)} | {sum(r[3]['success'] for r in band)} | "
                     f"{', '.join(f'{k} {v}' for k, v in sorted(outcomes.items()))} |")
    lines.append(f"\nDetour ratio of the successes: {spread(ratio[success])}; of the failures: {spread(ratio[~success])}.")
    publish("\n".join(lines), args.out)


if __name__ == "__main__":
    main()
