"""Measured statistics of the Meta-World clips for docs/metaworld.md, and a picture of some.

    python benchmarks/metaworld_stats.py --split val --out benchmarks/results/metaworld_stats.md \
        --figure docs/img/metaworld_clips.png

Reads a generated split (``keyin-generate dataset=metaworld``): clips per task, valid frames, labels
per clip, the gaps between labels (from the first frame) per task, and the spread of each phase's
length over the episodes of a task (the timing a fixed keyframe pattern cannot follow). The figure
shows the first clip of each task, its labelled frames framed in green.
"""

from __future__ import annotations

import argparse
import collections
from datetime import date
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

from common import cpu_model, dataset_config, publish
from keyin.data.hdf5 import load_arrays, split_files


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--split", default="val")
    parser.add_argument("--dataset", default="metaworld", help="metaworld or metaworld_v2")
    parser.add_argument("--data-dir", default="data")
    parser.add_argument("--out", type=Path)
    parser.add_argument("--figure", type=Path)
    args = parser.parse_args()
    config = dataset_config(args.dataset)
    tasks = list(config.generator.tasks)
    shards = [load_arrays(path) for path in split_files(Path(args.data_dir) / args.dataset, args.split)]
    arrays = {key: np.concatenate([shard[key] for shard in shards]) for key in ("keyframes", "length", "task")}
    gaps_by_task, counts, lengths = collections.defaultdict(list), collections.Counter(), collections.defaultdict(list)
    for keyframes, valid, task in zip(arrays["keyframes"], arrays["length"], arrays["task"]):
        marks = np.flatnonzero(keyframes)
        gaps_by_task[tasks[task]].append(np.diff(np.r_[0, marks]))
        counts[len(marks)] += 1
        lengths[tasks[task]].append(int(valid))
    every_gap = np.concatenate([g for rows in gaps_by_task.values() for g in rows])
    lines = [
        f"## Meta-World clips ({args.split}, {len(arrays['task'])} clips)\n",
        f"- command: `python benchmarks/metaworld_stats.py --split {args.split}"
        + ("" if args.dataset == "metaworld" else f" --dataset {args.dataset}") + "`",
        f"- machine: {cpu_model()}, {date.today()}; conf/dataset/{args.dataset}.yaml (frame_skip "
        f"{config.generator.frame_skip}, L = {config.n_cond + config.n_future})",
        f"- labels per clip: {', '.join(f'{k}: {v}' for k, v in sorted(counts.items()))}",
        f"- gaps between labels (saved frames, the first from frame 0): median {np.median(every_gap):.0f}, "
        f"{every_gap.min()}-{every_gap.max()}, 90 % <= {np.percentile(every_gap, 90):.0f}; histogram "
        f"{np.bincount(every_gap).tolist()}\n",
        "| task | clips | valid frames (median, range) | labels per clip | gap to each label, mean ± std over clips |",
        "|---|---|---|---|---|",
    ]
    for task in tasks:
        rows = gaps_by_task[task]
        if not rows:
            continue
        width = collections.Counter(len(r) for r in rows).most_common(1)[0][0]
        same = np.array([r for r in rows if len(r) == width])
        spread = ", ".join(f"{m:.1f} ± {s:.1f}" for m, s in zip(same.mean(0), same.std(0)))
        lines.append(f"| {task} | {len(rows)} | {np.median(lengths[task]):.0f} ({min(lengths[task])}-{max(lengths[task])}) | "
                     f"{np.mean([len(r) for r in rows]):.2f} | {spread} (the {len(same)} clips with {width}) |")
    publish("\n".join(lines), args.out)
    if args.figure:
        save_figure(shards, tasks, args.figure)


def save_figure(shards: list[dict[str, np.ndarray]], tasks: list[str], path: Path, scale: int = 2) -> None:
    """The first clip of each task, one row each, its labelled frames framed in green."""
    frames = np.concatenate([shard["frames"] for shard in shards])
    keyframes = np.concatenate([shard["keyframes"] for shard in shards])
    task_of = np.concatenate([shard["task"] for shard in shards])
    length = np.concatenate([shard["length"] for shard in shards])
    rows = [int(np.flatnonzero(task_of == t)[0]) for t in range(len(tasks)) if (task_of == t).any()]
    width = max(int(length[r]) for r in rows)
    size = frames.shape[2] * scale
    sheet = Image.new("RGB", (width * (size + 2), len(rows) * (size + 2)), "white")
    draw = ImageDraw.Draw(sheet)
    for y, row in enumerate(rows):
        for x in range(int(length[row])):
            image = Image.fromarray(frames[row, x]).resize((size, size), Image.NEAREST)
            sheet.paste(image, (x * (size + 2) + 1, y * (size + 2) + 1))
            if keyframes[row, x]:
                draw.rectangle([x * (size + 2), y * (size + 2), x * (size + 2) + size + 1, y * (size + 2) + size + 1],
                               outline=(0, 200, 0), width=2)
    path.parent.mkdir(parents=True, exist_ok=True)
    sheet.save(path)


if __name__ == "__main__":
    main()
