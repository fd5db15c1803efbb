"""The stage-2 gate: keyframe F1 of the exact best segmentation under a stage-1 checkpoint.

    python benchmarks/segmentation_gate.py runs/<run>/checkpoints/interpolator/last.ckpt --clips 200

Scores the first ``--clips`` test clips (``data/brownian`` test split; ``keyin-generate
dataset=brownian 'splits={test: 1000}'`` writes it) with :mod:`keyin.eval.segmentation`, and
compares the summed interpolation BCE of three hard segmentations: the DP optimum, the ground
truth, and Constant every ``c`` frames. Stage 2 can only discover what the DP finds.
"""

from __future__ import annotations

import argparse
import platform
import time
from datetime import date
from pathlib import Path

import torch
from torch.utils.data import Subset

from keyin.data.clips import ShardClips
from keyin.data.hdf5 import split_files
from keyin.eval.discovery import evaluate_discoverer
from keyin.eval.f1 import keyframe_lists
from keyin.eval.segmentation import SegmentationDiscoverer, best_segmentation, path_cost
from keyin.lit.checkpoints import load_checkpoint
from keyin.lit.interpolator import InterpolatorModule


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("ckpt")
    parser.add_argument("--clips", type=int, default=200)
    parser.add_argument("--keyframes", type=int, default=6)
    parser.add_argument("--constant", type=int, default=6)
    parser.add_argument("--space", default="pixels", choices=("pixels", "embeddings"))
    parser.add_argument("--data-dir", default="data/brownian")
    args = parser.parse_args()
    checkpoint = load_checkpoint(args.ckpt, "interpolator")
    stage1 = InterpolatorModule(**checkpoint["hyper_parameters"])
    stage1.load_state_dict(checkpoint["state_dict"])
    hp = stage1.hparams
    clips = ShardClips(split_files(Path(args.data_dir), "test"), (hp.image_size, hp.image_size, hp.channels),
                       hp.n_cond, hp.n_future)
    clips = Subset(clips, range(min(args.clips, len(clips))))
    discoverer = SegmentationDiscoverer(stage1, args.keyframes, args.space)
    started = time.perf_counter()
    scores = evaluate_discoverer(discoverer, clips, hp.n_future, batch_size=len(clips))
    seconds = time.perf_counter() - started
    batch = next(iter(torch.utils.data.DataLoader(clips, batch_size=len(clips))))
    costs = discoverer.last_costs
    truth = keyframe_lists(batch["keyframes"])
    constant = [list(range(args.constant - 1, hp.n_future - 1, args.constant))] * len(truth)
    _, dp_positions = best_segmentation(costs, args.keyframes)
    dp = path_cost(costs, dp_positions)
    n_dp = sum(map(len, dp_positions)) / len(dp_positions)
    print(f"## Segmentation gate: {args.ckpt}\n")
    print(f"- command: `python benchmarks/segmentation_gate.py {args.ckpt} --clips {args.clips} --space {args.space}`")
    print(f"- machine: {platform.machine()}, {torch.get_num_threads()} threads, torch {torch.__version__}, "
          f"{date.today()}; step {checkpoint.get('global_step')}; {seconds:.1f} s\n")
    print(f"| segmentation | mean summed cost ({args.space}) |")
    print("|---|---|")
    for name, positions_cost in [("DP optimum", dp), ("ground truth", path_cost(costs, truth)),
                                 (f"constant {args.constant}", path_cost(costs, constant))]:
        finite = positions_cost[torch.isfinite(positions_cost)]
        print(f"| {name} | {finite.mean():.1f} ({len(finite)} clips) |")
    print(f"\nDP keyframes vs ground truth: F1 {scores['f1']:.3f}, ±1 {scores['f1_tol1']:.3f}, "
          f"precision {scores['precision']:.3f}, recall {scores['recall']:.3f}, "
          f"{n_dp:.2f} keyframes/clip")


if __name__ == "__main__":
    main()
