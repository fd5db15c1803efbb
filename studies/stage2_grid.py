"""One row per arm of table=paper_stage2_grid: its options, test F1, validation curve end and diagnostics.

    python studies/stage2_grid.py docs/results/paper_stage2_grid --out docs/results/paper_stage2_grid/grid.md

Reads what the table commits: ``jobs/<arm>/metrics.json`` and ``config.yaml`` (keyin-reproduce's collect
step), ``validation.csv`` (studies/training_curves.py, labelled by arm) and ``diagnostics/<arm>.md``
(studies/stage2_diagnostics.py on the arm's checkpoint, 200 validation clips). The arms are ranked
by their last validation F1 (60 validation clips): the test columns only score.
"""

from __future__ import annotations

import argparse
import csv
import json
import sys
from pathlib import Path

import yaml

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # common.py stays with the benchmarks
from common import publish  # noqa: E402

OPTIONS = {  # config path → (column text, the value of a config written before the option existed)
    "model.keyframes.delta_input": ("δ to the interpolator", "soft"),
    "model.keyframes.loss_reduction": ("reduction", "sum"),
    "model.keyframes.frozen": ("frozen in stage 2", "stage1"),
    "model.keyframes.attn_scale": ("attention /√E", True),
    "loss.normalize_key_targets": ("K̃ / c", True),
    "scale.lr_stage2": ("lr", None),
    "scale.inter_latent": ("Zi", None),
    "model.keyframes.entropy_bonus": ("entropy aid", 0.0),
    "model.keyframes.gumbel_offsets": ("Gumbel aid", False),
    "interpolator_ckpt": ("stage 1", None),
}
DIAGNOSTICS = {
    "L_inter soft δ": "L_inter soft δ",
    "L_inter argmax δ, model K̂": "argmax δ, K̂",
    "L_inter true offsets, model K̂": "true δ, K̂",
    "L_inter true offsets, true frames": "true δ, true frames",
    "L_inter Constant-5, true frames": "Constant-5, true frames",
    "clips whose gradient raises keyframe 1's true offset": "gradient → true δ¹",
    "‖K̂ − e(frame)‖², keyframes inside": "‖K̂ − e‖²",
}


def lookup(config: dict, dotted: str):
    """The value at a dotted path of a config, or the option's value before it existed (:data:`OPTIONS`)."""
    for key in dotted.split("."):
        config = config.get(key, {}) if isinstance(config, dict) else {}
    return OPTIONS[dotted][1] if config == {} else config


def shown(value) -> str:
    """An option's value as the table shows it: a checkpoint path by its run folder's name."""
    text = str(value)
    return Path(text).parents[2].name if text.endswith(".ckpt") else text


def last_validation(table: Path) -> dict[str, dict[str, float]]:
    """Arm → its last validation row (F1, distinct patterns, entropy)."""
    rows: dict[str, dict[str, float]] = {}
    with open(table, newline="") as handle:
        for row in csv.DictReader(handle):
            if row["run"] not in rows or int(row["step"]) >= rows[row["run"]]["step"]:
                rows[row["run"]] = {key: float(value) for key, value in row.items() if key != "run"}
    return rows


def diagnostics(path: Path) -> dict[str, float]:
    if not path.is_file():
        return {}
    block = path.read_text().split("```json\n", 1)[1].split("\n```", 1)[0]
    return json.loads(block)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("folder", type=Path)
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    validation = last_validation(args.folder / "validation.csv") if (args.folder / "validation.csv").is_file() else {}
    jobs = sorted(path.parent for path in (args.folder / "jobs").glob("*/metrics.json"))
    baseline = yaml.safe_load((args.folder / "jobs" / "baseline" / "config.yaml").read_text())
    rows = []
    for job in jobs:
        metrics = json.loads((job / "metrics.json").read_text())
        config = yaml.safe_load((job / "config.yaml").read_text())
        changed = [f"{text} {shown(lookup(config, key))}" for key, (text, _) in OPTIONS.items() if lookup(config, key) != lookup(baseline, key)]
        curve = validation.get(job.name, {})
        rows.append((curve.get("val/f1", float("nan")), job.name, changed, metrics, curve, diagnostics(args.folder / "diagnostics" / f"{job.name}.md")))
    rows.sort(key=lambda row: -row[0])
    header = ["arm", "changed from the baseline", "val F1 (60, last)", "test F1", "test ±1 F1", "val patterns", "val δ entropy",
              *DIAGNOSTICS.values(), "train min"]
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for val_f1, name, changed, metrics, curve, diag in rows:
        cells = [name, ", ".join(changed) or "(the baseline)", f"{val_f1:.3f}", f"{metrics['f1']:.3f}", f"{metrics['f1_tol1']:.3f}",
                 f"{curve.get('val/distinct_patterns', float('nan')):.0f}", f"{curve.get('val/offset_entropy', float('nan')):.2f}",
                 *(f"{diag[key]:.3g}" if key in diag else "" for key in DIAGNOSTICS), f"{metrics.get('train_seconds', 0) / 60:.1f}"]
        lines.append("| " + " | ".join(cells) + " |")
    publish("\n".join(lines) + "\n", args.out)


if __name__ == "__main__":
    main()
