"""Measured statistics of the pushing datasets and planning tasks for docs/pushing.md.

    python benchmarks/pushing_stats.py --demos 400 --tasks 240 --figure docs/img/pushing_demos.png
    python benchmarks/pushing_stats.py --dataset pushing pushing_irregular --split val --demos 200 \
        --tasks 240 --out benchmarks/results/pushing_irregular_stats.md

Prints a Markdown table with a column per dataset (``--dataset``: conf/dataset/<name>.yaml's
generator), from the demos of the ``--split``'s first clips (physics only, the same labels as the
generated clips): acceptance rate, the histograms of push lengths, of pauses and of the gaps between
labels, keyframes per clip, detour sides, demo lengths and the fraction of padded clips, the
Random / Constant-c keyframe F1 (the paper's Table 1 rows; exact over all labels and the
interior column of docs/evaluation.md), and the initial shortest-path distance over ``--tasks``
planning tasks (the paper's "Initial" row, 1.32 ± 0.06). Draws a grid of the first dataset's
sample demos with subgoals and keyframes marked.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from datetime import date
from pathlib import Path

import numpy as np
import torch
from hydra.utils import instantiate

from common import cpu_model, dataset_config, publish
from keyin.data.generate import split_seed
from keyin.data.hdf5 import load_arrays
from keyin.data.pushing import PushingGenerator, write_planning_tasks
from keyin.decode.baselines import ConstantKeyframes, RandomKeyframes
from keyin.envs.demonstrator import detour_polyline
from keyin.envs.geometry import apply_homography, wall_corners
from keyin.eval.f1 import column_scores, keyframe_scores


def demo_statistics(generator: PushingGenerator, count: int, seed: int) -> dict:
    """Run ``count`` accepted demos (no rendering) and collect their statistics."""
    lengths, gaps, pauses, attempts, sides, saved, pushes_in_clip = [], [], [], [], [], [], []
    truth = []
    n = generator.n_future
    start = time.perf_counter()
    for index in range(count):
        demo, tries = generator.demo(index, seed)
        completions = demo.saved_completions(generator.frame_skip)
        lengths.append(demo.push_lengths(generator.frame_skip))
        gaps.append(np.diff(completions, prepend=0))
        pauses.append(demo.pauses[:-1])
        attempts.append(tries)
        sides.append(demo.side)
        saved.append(int(completions[-1]))
        future = completions - generator.n_cond  # future index of each keyframe
        truth.append([int(f) for f in future if f < n])
        pushes_in_clip.append(len(truth[-1]))
    return {"lengths": np.array(lengths), "gaps": np.array(gaps), "pauses": np.array(pauses),
            "attempts": np.array(attempts), "sides": np.array(sides), "saved": np.array(saved),
            "truth": truth, "pushes_in_clip": np.array(pushes_in_clip),
            "seconds_per_demo": (time.perf_counter() - start) / count}


def baseline_f1(
    truth: list[list[int]], future_length: np.ndarray, n: int, offsets: list[int], seed: int = 0
) -> tuple[tuple[float, float], dict[int, tuple[float, float]]]:
    """(exact F1 over all labels, interior F1) of Random (6 distinct valid frames) and of Constant
    (every c-th frame) for each c in ``offsets``."""
    lengths = torch.as_tensor(future_length)

    def scores(method: RandomKeyframes | ConstantKeyframes) -> tuple[float, float]:
        picks = method(None, lengths)  # neither baseline looks at the frames
        return keyframe_scores(picks, truth, n)["f1"], column_scores(picks, truth, lengths.tolist(), n)["f1_interior"]

    return scores(RandomKeyframes(6, seed)), {c: scores(ConstantKeyframes(c)) for c in offsets}


def histogram(values: np.ndarray) -> str:
    """``value: count (share)`` for each value that occurs."""
    keys, counts = np.unique(values, return_counts=True)
    return ", ".join(f"{k}: {c} ({c / values.size:.0%})" for k, c in zip(keys.tolist(), counts.tolist()))


def statistics_rows(stats: dict, n: int, n_keyframes: int, offsets: list[int]) -> dict[str, str]:
    """The table's rows for one dataset's :func:`demo_statistics`, in order."""
    lengths, gaps, saved, attempts = stats["lengths"], stats["gaps"], stats["saved"], stats["attempts"]
    rows = {
        "demos (s per demo, physics only)": f"{len(saved)} ({stats['seconds_per_demo']:.3f})",
        "acceptance rate": f"{len(attempts) / attempts.sum():.1%} ({attempts.sum()} drawn)",
        "push length in saved frames": f"{histogram(lengths)}; mean {lengths.mean():.2f}",
        "mean length of each push": ", ".join(f"{v:.2f}" for v in lengths.mean(0)),
        "pause after each push but the last, saved frames": f"{histogram(stats['pauses'])}; mean {stats['pauses'].mean():.2f}",
        "gap between labels (the first from the conditioning frame)": f"{histogram(gaps)}; mean {gaps.mean():.2f} ± {gaps.std():.2f}",
        "demo length after the first frame": f"mean {saved.mean():.1f}, {saved.min()}-{saved.max()}",
        f"padded clips (demo ends before N = {n})": f"{np.mean(saved < n):.1%}",
        "truncated clips (demo longer than N, keyframes lost)": f"{np.mean(saved > n):.1%}",
        "keyframes inside the clip": f"{histogram(stats['pushes_in_clip'])}; mean {stats['pushes_in_clip'].mean():.2f}",
        "detour side +1 / -1": f"{np.mean(stats['sides'] == 1):.1%} / {np.mean(stats['sides'] == -1):.1%}",
    }
    random, constant = baseline_f1(stats["truth"], np.minimum(saved, n), n, offsets)
    rows["Random: F1 interior (exact, all labels)"] = f"{random[1]:.3f} ({random[0]:.3f})"
    smallest = n // (n_keyframes + 1) + 1  # the smallest c that places at most M keyframes in a full clip
    for c, (exact, interior) in constant.items():
        note = " (more than M keyframes)" if c < smallest else ""
        rows[f"Constant c = {c}{note}: F1 interior (exact, all labels)"] = f"{interior:.3f} ({exact:.3f})"
    best = max((c for c in offsets if c >= smallest), key=lambda c: constant[c][1])
    rows["best Constant with at most M keyframes: F1 interior"] = f"**{constant[best][1]:.3f}** (c = {best})"
    return rows


def planning_rows(generator: PushingGenerator, tasks: int, seed: int) -> dict[str, str]:
    """The initial shortest-path distance over ``tasks`` planning tasks (the paper's "Initial")."""
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "planning.h5"
        write_planning_tasks(path, generator, n=tasks, seed=seed)
        distance = load_arrays(path, ("initial_distance",))["initial_distance"]
    return {f"initial shortest-path distance, {tasks} planning tasks (paper: 1.32 ± 0.06)":
            f"{distance.mean():.3f} ± {distance.std():.3f} ({distance.min():.2f}-{distance.max():.2f}; "
            f"{time.perf_counter() - start:.0f} s)"}


def draw_figure(generator: PushingGenerator, path: Path, rows: int, seed: int) -> None:
    """Rows of demos: an overview (first frame, puck path, detour, subgoals) and the 6 keyframes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    homography = generator.environment().physics.homography()
    columns = 1 + generator.n_pushes
    figure, axes = plt.subplots(rows, columns, figsize=(1.35 * columns, 1.6 * rows))
    for row in range(rows):
        arrays, _ = generator.generate(row, seed)
        demo, _ = generator.demo(row, seed)
        frames, valid = arrays["frames"], int(arrays["length"])
        overview = axes[row, 0]
        overview.imshow(frames[0], extent=(0, 64, 64, 0))
        track = apply_homography(homography, arrays["puck"][:valid])
        overview.plot(track[:, 0], track[:, 1], "-", color="black", lw=0.8)
        polyline = apply_homography(homography, detour_polyline(demo.layout, demo.side, 0.06, 0.1))
        overview.plot(polyline[:, 0], polyline[:, 1], ":", color="white", lw=0.8)
        corners = apply_homography(homography, wall_corners(demo.layout.wall, generator.puck_radius))
        overview.plot(*np.vstack([corners, corners[:1]]).T, "-", color="cyan", lw=0.5)
        subgoals = apply_homography(homography, arrays["subgoals"])
        overview.scatter(subgoals[:, 0], subgoals[:, 1], marker="x", s=14, color="red", lw=1)
        for k, (u, v) in enumerate(subgoals):
            overview.text(u + 1.5, v - 1.5, str(k + 1), color="red", fontsize=5)
        overview.set_title(f"demo {row}: {valid - 1} future frames", fontsize=6)
        keyframes = np.flatnonzero(arrays["keyframes"])
        for column in range(1, columns):
            axis = axes[row, column]
            if column - 1 < len(keyframes):
                clip_index = keyframes[column - 1]
                axis.imshow(frames[clip_index])
                axis.set_title(f"key {column}: t={clip_index - generator.n_cond}", fontsize=6, color="red")
                for spine in axis.spines.values():
                    spine.set_edgecolor("red")
                    spine.set_linewidth(1.5)
            else:
                axis.set_title("past N", fontsize=6)
                axis.set_facecolor("0.9")
        for axis in axes[row]:
            axis.set_xticks([])
            axis.set_yticks([])
    figure.tight_layout(pad=0.3)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=110)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--dataset", nargs="+", default=["pushing"], help="conf/dataset/<name>.yaml, one column each")
    parser.add_argument("--split", default="train", help="whose clips' demos are measured")
    parser.add_argument("--demos", type=int, default=400)
    parser.add_argument("--tasks", type=int, default=240, help="planning tasks (0: none)")
    parser.add_argument("--offsets", type=int, nargs="+", default=list(range(3, 12)), help="Constant's spacings c")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--figure", type=Path, default=None)
    parser.add_argument("--figure-rows", type=int, default=4)
    parser.add_argument("--out", type=Path, help="also write the Markdown here")
    args = parser.parse_args()
    load = os.getloadavg()[0]
    columns = {}
    for name in args.dataset:
        config = dataset_config(name)
        generator = instantiate(config.generator)
        rows = statistics_rows(demo_statistics(generator, args.demos, split_seed(args.seed, args.split)),
                               generator.n_future, config.n_keyframes, args.offsets)
        columns[name] = {**rows, **(planning_rows(generator, args.tasks, args.seed) if args.tasks else {})}
    command = " ".join(["python benchmarks/pushing_stats.py", f"--dataset {' '.join(args.dataset)}", f"--split {args.split}",
                        f"--demos {args.demos}", f"--tasks {args.tasks}"])
    lines = [f"## Pushing demonstrations: {args.demos} demos of the {args.split} clips (data seed {args.seed})\n",
             f"- command: `{command}`",
             f"- machine: {cpu_model()}, {os.cpu_count()} cores, torch {torch.__version__}, {date.today()}; "
             f"load average before / after: {load:.2f} / {os.getloadavg()[0]:.2f}\n",
             "| statistic | " + " | ".join(columns) + " |", "|---" * (len(columns) + 1) + "|"]
    lines += [f"| {row} | " + " | ".join(column[row] for column in columns.values()) + " |" for row in columns[args.dataset[0]]]
    publish("\n".join(lines), args.out)
    if args.figure:
        generator = instantiate(dataset_config(args.dataset[0]).generator)
        draw_figure(generator, args.figure, args.figure_rows, split_seed(args.seed, "val"))
        print(f"\nfigure: {args.figure} ({args.figure.stat().st_size / 1024:.0f} KiB)")


if __name__ == "__main__":
    main()
