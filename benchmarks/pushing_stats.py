"""Measured statistics of the pushing dataset and planning tasks for docs/pushing.md.

    python benchmarks/pushing_stats.py --demos 400 --tasks 240 --figure docs/img/pushing_demos.png

Prints Markdown: acceptance rate, push-length histogram, pushes per clip, detour sides, clip
lengths, the initial shortest-path distance over the planning tasks (the paper's "Initial" row,
1.32 ± 0.06), and the Random / Constant keyframe-F1 sanity rows (REFERENCE §6.2). Draws a grid of
sample demos with subgoals and keyframes marked.
"""

from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from keyin.data.generate import split_seed
from keyin.data.hdf5 import load_arrays
from keyin.data.pushing import PushingGenerator, write_planning_tasks
from keyin.envs.demonstrator import detour_polyline
from keyin.envs.geometry import apply_homography, wall_corners
from keyin.eval.f1 import keyframe_scores


def demo_statistics(generator: PushingGenerator, count: int, seed: int) -> dict:
    """Run ``count`` accepted demos (no rendering) and collect their statistics."""
    lengths, attempts, sides, saved, pushes_in_clip = [], [], [], [], []
    truth = []
    n = generator.n_future
    for index in range(count):
        demo, tries = generator.demo(index, seed)
        push = demo.push_lengths(generator.frame_skip)
        completions = demo.saved_completions(generator.frame_skip)
        lengths.append(push)
        attempts.append(tries)
        sides.append(demo.side)
        saved.append(int(completions[-1]))
        future = completions - generator.n_cond  # future index of each keyframe
        truth.append([int(f) for f in future if f < n])
        pushes_in_clip.append(len(truth[-1]))
    return {"lengths": np.array(lengths), "attempts": np.array(attempts), "sides": np.array(sides),
            "saved": np.array(saved), "truth": truth, "pushes_in_clip": np.array(pushes_in_clip)}


def baseline_f1(truth: list[list[int]], valid_future: np.ndarray, n: int, seed: int = 0) -> dict:
    """Random (6 distinct valid frames) and Constant (c = 4, 5) keyframe F1 against the ground truth."""
    rng = np.random.default_rng(seed)
    random_picks = [sorted(rng.choice(v, size=min(6, v), replace=False).tolist()) for v in valid_future]
    scores = {"random": keyframe_scores(random_picks, truth, n)["f1"]}
    for offset in (4, 5):
        picks = [list(range(offset - 1, v, offset)) for v in valid_future]
        scores[f"constant_{offset}"] = keyframe_scores(picks, truth, n)["f1"]
    return scores


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
    parser.add_argument("--demos", type=int, default=400)
    parser.add_argument("--tasks", type=int, default=240)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--figure", type=Path, default=None)
    parser.add_argument("--figure-rows", type=int, default=4)
    args = parser.parse_args()
    generator = PushingGenerator()
    n = generator.n_future

    start = time.perf_counter()
    stats = demo_statistics(generator, args.demos, split_seed(args.seed, "train"))
    lengths = stats["lengths"]
    print(f"## {args.demos} training demos (seed {args.seed}; {time.perf_counter() - start:.0f} s)\n")
    attempts = stats["attempts"]
    print(f"- acceptance rate: {len(attempts) / attempts.sum():.1%} ({attempts.sum()} demos drawn)")
    histogram = {int(k): int(c) for k, c in zip(*np.unique(lengths, return_counts=True))}
    print(f"- push length (saved frames): histogram {histogram}, mean {lengths.mean():.2f}")
    print(f"- mean push length by push 1-6: {np.round(lengths.mean(0), 2).tolist()}")
    print(f"- pushes per demo: {lengths.shape[1]}; keyframes inside the clip (future index < {n}): "
          f"mean {stats['pushes_in_clip'].mean():.2f}, histogram "
          f"{dict(zip(*[a.tolist() for a in np.unique(stats['pushes_in_clip'], return_counts=True)]))}")
    sides = stats["sides"]
    print(f"- detour side +1 / -1: {np.mean(sides == 1):.1%} / {np.mean(sides == -1):.1%}")
    saved = stats["saved"]
    print(f"- demo length (saved frames after the first): mean {saved.mean():.1f}, min {saved.min()}, "
          f"max {saved.max()}; truncated to N = {n}: {np.mean(saved > n):.1%}")
    valid_future = np.minimum(saved, n)
    for name, value in baseline_f1(stats["truth"], valid_future, n).items():
        print(f"- {name} keyframe F1 (exact): {value:.3f}")

    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "planning.h5"
        write_planning_tasks(path, generator, n=args.tasks, seed=args.seed)
        tasks = load_arrays(path, ("initial_distance", "start", "goal"))
    distance = tasks["initial_distance"]
    print(f"\n## {args.tasks} planning tasks ({time.perf_counter() - start:.0f} s)\n")
    print(f"- initial shortest-path distance: {distance.mean():.3f} ± {distance.std():.3f} "
          f"(min {distance.min():.3f}, max {distance.max():.3f}); paper: 1.32 ± 0.06")
    if args.figure:
        draw_figure(generator, args.figure, args.figure_rows, split_seed(args.seed, "val"))
        print(f"\nfigure: {args.figure} ({args.figure.stat().st_size / 1024:.0f} KiB)")


if __name__ == "__main__":
    main()
