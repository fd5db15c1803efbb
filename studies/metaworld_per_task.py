"""Meta-World Table 1 per task: interior F1 of every method's test predictions on the clips of each task.

    python studies/metaworld_per_task.py docs/results/metaworld_table1/jobs \
        --out studies/results/metaworld_per_task.md
    python studies/metaworld_per_task.py docs/results/metaworld_v2_table1/jobs --dataset metaworld_v2 \
        --out studies/results/metaworld_v2_per_task.md

Reads each job's ``predictions.json`` (keyin-eval's per-clip truth, lengths and predictions) and the
test split's ``task`` array; seeds of a method are pooled (their clips counted once per seed).
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
from common import cpu_model, dataset_config, publish  # noqa: E402
from keyin.data.hdf5 import load_arrays, split_files  # noqa: E402
from keyin.eval.f1 import column_scores  # noqa: E402
from keyin.eval.report import method_sort_key  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("jobs", type=Path)
    parser.add_argument("--dataset", default="metaworld", help="the jobs' dataset (metaworld or metaworld_v2)")
    parser.add_argument("--data-dir", default="data")
    parser.add_argument("--out", type=Path)
    args = parser.parse_args()
    config = dataset_config(args.dataset)
    tasks = list(config.generator.tasks)
    task_of = np.concatenate([load_arrays(p)["task"] for p in split_files(Path(args.data_dir) / args.dataset, "test")])
    pooled: dict[str, dict[str, list]] = collections.defaultdict(lambda: collections.defaultdict(list))
    for path in sorted(args.jobs.glob("*/predictions.json")):
        saved = json.loads(path.read_text())
        for method, predicted in saved["predicted"].items():
            for clip, truth, length, found in zip(saved["clips"], saved["truth"], saved["lengths"], predicted):
                for key, value in (("truth", truth), ("lengths", length), ("predicted", found), ("task", tasks[task_of[clip]])):
                    pooled[method][key].append(value)
    header = "| method | " + " | ".join(tasks) + " | all |"
    lines = [
        f"## Meta-World ({args.dataset}): interior F1 per task ({args.jobs})\n",
        f"- command: `python studies/metaworld_per_task.py {args.jobs} --dataset {args.dataset}`",
        f"- machine: {cpu_model()}, {date.today()}; each method's seeds pooled\n",
        header, "|" + "---|" * (len(tasks) + 2),
    ]
    for method in sorted(pooled, key=method_sort_key):
        rows = pooled[method]
        cells = []
        for task in [*tasks, None]:
            pick = [i for i, t in enumerate(rows["task"]) if task is None or t == task]
            scores = column_scores([rows["predicted"][i] for i in pick], [rows["truth"][i] for i in pick],
                                   [rows["lengths"][i] for i in pick], config.n_future)
            cells.append(f"{scores['f1_interior']:.3f}")
        lines.append(f"| {method} | " + " | ".join(cells) + " |")
    publish("\n".join(lines), args.out)


if __name__ == "__main__":
    main()
