"""Validation curves of stage-2 runs from their Lightning CSV logs: keyframe F1, distinct keyframe
patterns among the validation clips and the offsets' entropy against the training step.

    python studies/training_curves.py <label>=<run dir or metrics CSV> [...] \
        --out docs/results/stage2_curves/curves.png --table docs/results/stage2_curves/validation.csv

A run dir's every ``csv/version_<n>/metrics.csv`` is read (a resumed run adds a version), or one CSV of such rows (a job's
committed record, docs/results/keyin_paper_stated/jobs/<job>/stage2_metrics.csv); rows of a stage other than stage 2
(no ``val/offset_entropy``) are left out. The validation rows are also written
as one CSV, small enough to commit, so the figure can be redrawn after the run dir is gone.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

CURVES = {"val/f1": "keyframe F1 (argmax offsets)", "val/distinct_patterns": "distinct patterns", "val/offset_entropy": "offset entropy (nats)"}


def validation_rows(run: Path) -> list[dict[str, float]]:
    """Stage 2's validation rows of ``run`` (a metrics CSV, or every CSV log under a run dir in the order the versions
    ran), by step (the last one per step)."""
    rows: dict[int, dict[str, float]] = {}
    logs = sorted(run.glob("csv/version_*/metrics.csv"), key=lambda path: int(path.parent.name.split("_")[1]))
    for path in [run] if run.is_file() else logs:
        with open(path, newline="") as handle:
            for row in csv.DictReader(handle):
                if row.get("val/f1") and row.get("val/offset_entropy"):
                    rows[int(row["step"])] = {"step": int(row["step"]), **{key: float(row[key]) for key in CURVES}}
    return [rows[step] for step in sorted(rows)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", help="<label>=<run dir or metrics CSV>")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--table", type=Path, required=True)
    args = parser.parse_args()
    runs = {label: validation_rows(Path(folder)) for label, _, folder in (run.rpartition("=") for run in args.runs)}
    fig, axes = plt.subplots(1, len(CURVES), figsize=(4.2 * len(CURVES), 3.2))
    for label, rows in runs.items():
        for axis, (key, title) in zip(axes, CURVES.items()):
            axis.plot([row["step"] for row in rows], [row[key] for row in rows], marker=".", label=label)
            axis.set_title(title)
            axis.set_xlabel("stage-2 step")
    axes[0].set_ylim(0, 1)  # F1 on its whole range: a flat curve looks flat
    axes[0].legend(fontsize=8)
    fig.tight_layout()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    args.table.parent.mkdir(parents=True, exist_ok=True)
    with open(args.table, "w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=["run", "step", *CURVES])
        writer.writeheader()
        for label, rows in runs.items():
            writer.writerows({"run": label, **row} for row in rows)
    for label, rows in runs.items():
        last = rows[-1] if rows else {}
        print(f"{label}: {len(rows)} validations, last at step {last.get('step')}: F1 {last.get('val/f1', float('nan')):.3f}, "
              f"{last.get('val/distinct_patterns', float('nan')):.0f} patterns")
    print(f"wrote {args.out} and {args.table}")


if __name__ == "__main__":
    main()
