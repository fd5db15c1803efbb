"""The stage-2 gate: keyframe F1 of the exact best segmentation under a stage-1 checkpoint.

    python benchmarks/segmentation_gate.py runs/<run>/checkpoints/interpolator/last.ckpt --clips 200

Scores the first ``--clips`` test clips (``data/brownian`` test split; ``keyin-generate
dataset=brownian 'splits={test: 1000}'`` writes it) with :mod:`keyin.decode.segmentation`, and
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
from keyin.decode.segment_costs import embedding_costs, interpolation_costs
from keyin.decode.segmentation import best_segmentation, path_cost
from keyin.eval.f1 import keyframe_lists, keyframe_scores
from keyin.lit.checkpoints import load_checkpoint
from keyin.lit.interpolator import InterpolatorModule
from keyin.losses.image import future_pixel_weights


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
    batch = next(iter(torch.utils.data.DataLoader(clips, batch_size=len(clips))))  # full-length clips
    started = time.perf_counter()
    with torch.no_grad():
        boundary_emb = stage1.encoder(batch["frames"])[:, hp.n_cond - 1 :]  # (B, N + 1, E)
        if args.space == "embeddings":
            costs = embedding_costs(stage1.interpolator, boundary_emb)
        else:
            weights = future_pixel_weights(stage1.pixel_weights(batch["frames"]), hp.n_cond)
            costs = interpolation_costs(
                stage1.interpolator, stage1.decoder, boundary_emb, batch["frames"][:, hp.n_cond :].flatten(2), weights
            )
    _, dp_positions = best_segmentation(costs, args.keyframes)
    seconds = time.perf_counter() - started
    truth = keyframe_lists(batch["keyframes"])
    scores = keyframe_scores(dp_positions, truth, hp.n_future)
    constant = [list(range(args.constant - 1, hp.n_future - 1, args.constant))] * len(truth)
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
