"""Choose the change-point baseline's signal, cost and penalty on validation clips.

    python benchmarks/choose_changepoint.py --dataset brownian --clips 300 \
        --out benchmarks/results/choose_changepoint_brownian.md

Every (signal, cost, penalty) of the grid runs PELT (keyin/decode/changepoint.py) on the first
``--clips`` clips of the validation split; the row of best interior F1 (docs/evaluation.md) is
what ``dataset.tuned.changepoint`` holds. Validation clips only: the test split stays for the
reported F1.
"""

from __future__ import annotations

import argparse
import itertools
import time
from datetime import date

import numpy as np
import torch

from common import clip_arguments, cpu_model, publish, split_batch
from keyin.decode.changepoint import COSTS, SIGNALS, ChangepointKeyframes
from keyin.eval.f1 import column_scores, keyframe_lists

PENALTIES = [float(p) for p in np.round(np.logspace(-2, 5, 15), 4)]


def main() -> None:
    parser = clip_arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), clips=300)
    parser.add_argument("--dataset", default="brownian")
    parser.add_argument("--signals", nargs="+", default=list(SIGNALS), choices=SIGNALS)
    parser.add_argument("--costs", nargs="+", default=list(COSTS), choices=COSTS)
    args = parser.parse_args()
    dataset, batch = split_batch(args.dataset, args.split, args.clips, args.data_dir)
    truth, lengths = keyframe_lists(batch["keyframes"]), batch["future_length"].tolist()
    started = time.perf_counter()
    results = []
    frames = batch["frames"].numpy()
    for signal, cost in itertools.product(args.signals, args.costs):
        finder = ChangepointKeyframes(dataset.n_keyframes, dataset.n_cond, 0.0, signal, cost)
        detectors = [finder.detector(clip, length) for clip, length in zip(frames, lengths)]  # fitted once
        for penalty in PENALTIES:
            predicted = [finder.positions(detector, length, penalty) for detector, length in zip(detectors, lengths)]
            results.append((signal, cost, penalty, column_scores(predicted, truth, lengths, dataset.n_future)))
    seconds = time.perf_counter() - started
    best = max(results, key=lambda row: row[3]["f1_interior"])
    rows = ["| signal | cost | penalty | F1 interior | ±1 F1 interior | F1 with ends | keyframes/clip (interior) |",
            "|---|---|---|---|---|---|---|"]
    for signal, cost, penalty, s in results:
        mark = "**" if (signal, cost, penalty) == best[:3] else ""
        rows.append(f"| {signal} | {cost} | {penalty:g} | {mark}{s['f1_interior']:.3f}{mark} | {s['f1_tol1_interior']:.3f} | "
                    f"{s['f1_with_ends']:.3f} | {s['n_predicted_interior']:.2f} |")
    report = "\n".join([
        f"## Change-point baseline: signal, cost and penalty on {len(batch['frames'])} {args.split} clips ({args.dataset})\n",
        f"- command: `python benchmarks/choose_changepoint.py --dataset {args.dataset} --clips {args.clips} --split {args.split} "
        f"--signals {' '.join(args.signals)} --costs {' '.join(args.costs)}`",
        f"- machine: {cpu_model()}, torch {torch.__version__}, {date.today()}; {len(results)} settings in {seconds:.0f} s",
        f"- best (interior F1): signal `{best[0]}`, cost `{best[1]}`, penalty {best[2]:g} → F1 "
        f"{best[3]['f1_interior']:.3f} (±1 {best[3]['f1_tol1_interior']:.3f}); true keyframes per clip "
        f"(interior) {best[3]['n_true_interior']:.2f}\n",
        *rows,
    ])
    publish(report, args.out)


if __name__ == "__main__":
    main()
