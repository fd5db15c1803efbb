"""Brownian test-set statistics and generation speed (issue "Foundation"; paper §4.1.1).

    python benchmarks/brownian_stats.py --clips 1000

Prints Markdown: the histogram of ground-truth keyframes per clip among the N future frames, how
often each future index is a keyframe, the Random and Constant keyframe F1 (Constant for every
offset 4..8, to show how the phase of the keyframes decides it), and clips/s of the generator
alone (one process) and of `generate_dataset` with 1 and 2 workers (HDF5 shards included).
"""

from __future__ import annotations

import argparse
import platform
import tempfile
import time
from collections import Counter
from datetime import date
from pathlib import Path

import numpy as np
import torch

from keyin.data.brownian import BrownianGenerator
from keyin.data.generate import generate_dataset, split_seed
from keyin.decode.baselines import ConstantKeyframes, RandomKeyframes
from keyin.eval.f1 import keyframe_scores

DATA_SEED = 0  # conf/dataset/brownian.yaml


def future_keyframes(generator: BrownianGenerator, clips: int, seed: int) -> list[list[int]]:
    """Ground-truth future indices of the test clips, exactly as keyin-generate stores them."""
    truth = []
    for index in range(clips):
        arrays, _ = generator.generate(index, seed)
        flags = arrays["keyframes"][generator.n_cond :]
        truth.append(np.flatnonzero(flags).tolist())
    return truth


def baseline_rows(truth: list[list[int]], n_future: int) -> list[tuple[str, dict]]:
    lengths = torch.full((len(truth),), n_future)
    rows = [("Random (6 distinct frames)", RandomKeyframes(6, seed=0)(None, lengths))]
    rows += [(f"Constant, every {c} frames", ConstantKeyframes(c)(None, lengths)) for c in range(4, 9)]
    return [(name, keyframe_scores(pred, truth, n_future)) for name, pred in rows]


def generation_speed(generator: BrownianGenerator, clips: int) -> list[tuple[str, float]]:
    start = time.perf_counter()
    for index in range(clips):
        generator.generate(index, 0)
    rows = [("generator only, 1 process", clips / (time.perf_counter() - start))]
    config = {"generator": "brownian-benchmark"}
    for workers in (1, 2):
        with tempfile.TemporaryDirectory() as folder:
            stats = generate_dataset(
                generator, Path(folder), "brownian", {"train": clips}, shard_size=500,
                seed=DATA_SEED, workers=workers, config=config, progress=False,
            )
        rows.append((f"keyin-generate path, {workers} worker(s), HDF5 shards", stats["clips_per_s"]))
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", type=int, default=1000)
    args = parser.parse_args()
    generator = BrownianGenerator()
    n_future = generator.n_future
    truth = future_keyframes(generator, args.clips, split_seed(DATA_SEED, "test"))
    counts = Counter(len(t) for t in truth)
    per_index = np.bincount([i for t in truth for i in t], minlength=n_future) / args.clips

    print(f"## Brownian test set: {args.clips} clips (data seed {DATA_SEED}, split test)\n")
    print(f"- command: `python benchmarks/brownian_stats.py --clips {args.clips}`")
    print(f"- machine: {platform.processor() or platform.machine()}, {torch.get_num_threads()} threads, "
          f"torch {torch.__version__}, Python {platform.python_version()}, {date.today()}\n")
    mean = np.mean([len(t) for t in truth])
    print(f"Ground-truth keyframes per clip among the {n_future} future frames (mean {mean:.2f}):\n")
    print("| keyframes | " + " | ".join(str(k) for k in sorted(counts)) + " |")
    print("|---|" + "---|" * len(counts))
    print("| clips | " + " | ".join(str(counts[k]) for k in sorted(counts)) + " |\n")
    print("Fraction of clips with a keyframe at each future index:\n")
    print("| index | " + " | ".join(str(i) for i in range(n_future)) + " |")
    print("|---|" + "---|" * n_future)
    print("| P | " + " | ".join(f"{p:.2f}" for p in per_index) + " |\n")
    print("| baseline | F1 | precision | recall | ±1 F1 | predicted/clip |")
    print("|---|---|---|---|---|---|")
    for name, s in baseline_rows(truth, n_future):
        print(f"| {name} | {s['f1']:.3f} | {s['precision']:.3f} | {s['recall']:.3f} | "
              f"{s['f1_tol1']:.3f} | {s['n_predicted']:.2f} |")
    print("\n| generation | clips/s |")
    print("|---|---|")
    for name, speed in generation_speed(generator, args.clips):
        print(f"| {name} | {speed:.0f} |")


if __name__ == "__main__":
    main()
