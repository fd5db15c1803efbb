"""Curves of the warm-start studies (studies/warm_start_arms.py) from their committed JSON: argmax-offset F1, keyframes
per clip, distinct patterns among the validation clips, δ's entropy, the paper's loss and its terms L_inter, L_ke and the
keyframe KL against the step (issue 62 item 2; L_ki is off, β_ki = 0, so not drawn).

    python studies/warm_start_curves.py "paper's loss, seed 0=docs/results/warm_start_brownian/arms.json:sampled" ... \
        --out docs/results/warm_start_brownian/curves.png

Each run is ``<label>=<json>:<arm>``; a label shared by several runs (seeds) draws them in one colour. Rows of a placed
phase (``phase: placed``) are drawn dashed.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

PANELS = {"f1": "argmax-offset F1", "keys": "keyframes per clip", "patterns": "distinct patterns", "entropy": "δ's entropy (nats)",
          "loss": "the loss (nats per clip)", "inter": "L_inter (nats per clip)", "key_emb": "L_ke (per clip)",
          "kl": "keyframe KL (nats per clip)"}
COLUMNS = 4


def arm_rows(spec: str) -> list[dict]:
    """The rows of ``<json>:<arm>``: the arm's validations, every ``--every`` steps, as the study wrote them."""
    path, _, arm = spec.rpartition(":")
    runs = json.loads(Path(path).read_text())
    if arm not in runs:
        raise SystemExit(f"{path} has no arm {arm!r}; it has {[key for key, value in runs.items() if isinstance(value, list)]}")
    return runs[arm]


def draw(runs: list[tuple[str, list[dict]]], out: Path) -> None:
    """One panel per :data:`PANELS` entry, one line per run, the runs of a label in one colour."""
    rows_of_panels = -(-len(PANELS) // COLUMNS)
    fig, axes = plt.subplots(rows_of_panels, COLUMNS, figsize=(3.6 * COLUMNS, 3.0 * rows_of_panels + 0.5))
    axes = axes.ravel()
    colours: dict[str, str] = {}
    for label, rows in runs:
        colour = colours.setdefault(label, f"C{len(colours)}")
        for axis, key in zip(axes, PANELS):
            placed = [row for row in rows if row.get("phase") == "placed"]
            released = [row for row in rows if row.get("phase") != "placed"]
            if placed:
                axis.plot([r["step"] for r in placed + released[:1]], [r[key] for r in placed + released[:1]], "--", color=colour)
            axis.plot([r["step"] for r in released], [r[key] for r in released], marker=".", color=colour,
                      label=label if key == "f1" and axis.get_legend_handles_labels()[1].count(label) == 0 else None)
    for axis, title in zip(axes, PANELS.values()):
        axis.set_title(title, fontsize=10)
        axis.set_xlabel("step")
    axes[0].set_ylim(0, 1)  # F1 on its whole range: small moves look small
    fig.legend(*axes[0].get_legend_handles_labels(), loc="upper center", ncol=min(4, len(colours)), fontsize=8)
    fig.tight_layout(rect=(0, 0, 1, 0.92))
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("runs", nargs="+", help="<label>=<json>:<arm>")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    runs = [(label, arm_rows(spec)) for label, _, spec in (run.rpartition("=") for run in args.runs)]
    draw(runs, args.out)
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
