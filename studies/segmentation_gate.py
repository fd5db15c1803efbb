"""The stage-2 gate: keyframe F1 of the exact best segmentation under a stage-1 checkpoint.

    python studies/segmentation_gate.py runs/<run>/checkpoints/interpolator/last.ckpt --clips 200
    python studies/segmentation_gate.py <ckpt> --data-dir data/pushing --split val --space embeddings

Scores the first ``--clips`` clips of a split (default: ``data/brownian``'s test split; ``keyin-generate
dataset=brownian 'splits={test: 1000}'`` writes it) with :mod:`keyin.decode.segmentation`, each clip
within its own valid frames, and compares the summed interpolation cost (pixel BCE, or squared error
of the embeddings) of three hard segmentations: the DP optimum, the ground truth, and Constant every
``c`` frames (over the clips where none of the three has a gap longer than S; before 2026-12-05 over
the full-length clips only). The DP's keyframes are scored by the information rule's two columns (a padded clip's sequence end removed from both sides, or given to both). Stage 2 can only
discover what the DP finds. The same is then done with the length prior removed: each offset's mean
cost over the scored clips subtracted from its segments (label-free), so that a spacing is not
preferred for its segment lengths alone (interpolation costs grow faster than linearly with the
offset, which favours an even spacing).
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
from keyin.decode.segmentation import decode_by_length, path_cost
from keyin.eval.f1 import column_scores, keyframe_lists
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
    parser.add_argument("--split", default="test")
    args = parser.parse_args()
    checkpoint = load_checkpoint(args.ckpt, "interpolator")
    stage1 = InterpolatorModule(**checkpoint["hyper_parameters"])
    stage1.load_state_dict(checkpoint["state_dict"])
    hp = stage1.hparams
    clips = ShardClips(split_files(Path(args.data_dir), args.split), (hp.image_size, hp.image_size, hp.channels),
                       hp.n_cond, hp.n_future)
    clips = Subset(clips, range(min(args.clips, len(clips))))
    batch = next(iter(torch.utils.data.DataLoader(clips, batch_size=len(clips))))  # every clip at once
    started = time.perf_counter()
    lengths = batch["future_length"]  # (B,) valid future frames
    with torch.no_grad():
        boundary_emb = stage1.encoder(batch["frames"])[:, hp.n_cond - 1 :]  # (B, N + 1, E)
        weights = future_pixel_weights(stage1.pixel_weights(batch["frames"]), hp.n_cond)
        frames = batch["frames"][:, hp.n_cond :].flatten(2)  # (B, N, D)

        by_length: dict[int, torch.Tensor] = {}  # the costs of each length's clips, as the DP asked for them

        def segment_costs(rows: torch.Tensor, length: int) -> torch.Tensor:
            """(R, length, S) costs of the clips ``rows``, within their ``length`` valid frames."""
            if args.space == "embeddings":
                costs = embedding_costs(stage1.interpolator, boundary_emb[rows, : length + 1])
            else:
                costs = interpolation_costs(stage1.interpolator, stage1.decoder, boundary_emb[rows, : length + 1],
                                            frames[rows, :length], None if weights is None else weights[rows, :length])
            by_length[length] = costs
            return costs

        dp_positions = decode_by_length(segment_costs, lengths, args.keyframes, hp.max_offset)
    seconds = time.perf_counter() - started
    print(f"## Segmentation gate: {args.ckpt}\n")
    print(f"- command: `python studies/segmentation_gate.py {args.ckpt} --clips {args.clips} --space {args.space} "
          f"--data-dir {args.data_dir} --split {args.split} --keyframes {args.keyframes} --constant {args.constant}`")
    print(f"- machine: {platform.machine()}, {torch.get_num_threads()} threads, torch {torch.__version__}, "
          f"{date.today()}; step {checkpoint.get('global_step')}; {seconds:.1f} s")
    truth = keyframe_lists(batch["keyframes"])
    report(args, "segment costs", by_length, dp_positions, truth, lengths, hp.n_future)
    length_prior = offset_means(by_length)  # (S,) what a segment of each offset costs on average
    centred = {length: costs - length_prior for length, costs in by_length.items()}
    # the DP asks for each length's rows in the same order as above, so the cached tables are theirs
    centred_positions = decode_by_length(lambda rows, length: centred[length], lengths, args.keyframes, hp.max_offset)
    print(f"\nThe length prior removed: each offset's mean cost over these clips ({', '.join(f'{m:.1f}' for m in length_prior.tolist())})"
          " subtracted, so that no spacing is cheaper for its lengths alone.")
    report(args, "segment costs minus their offset's mean", centred, centred_positions, truth, lengths, hp.n_future)


def offset_means(by_length: dict[int, torch.Tensor]) -> torch.Tensor:
    """(S,) mean cost of the in-clip segments of each offset, over every clip and start."""
    costs = torch.cat([table.flatten(0, 1) for table in by_length.values()])  # (R, S)
    inside = costs.isfinite()
    return torch.where(inside, costs, 0.0).sum(0) / inside.sum(0).clamp(min=1)


def report(args: argparse.Namespace, name: str, by_length: dict[int, torch.Tensor], dp_positions: list[list[int]],
           truth: list[list[int]], lengths: torch.Tensor, n_future: int) -> None:
    """Print the summed ``name`` of the DP optimum, the labels and Constant every ``args.constant``
    frames, each clip within its own valid frames, over the clips where all three fit (no gap over S),
    and the DP's keyframe scores by the information rule's two columns."""
    totals: dict[str, list[torch.Tensor]] = {"DP optimum": [], "ground truth": [], f"constant {args.constant}": []}
    for length, costs in sorted(by_length.items()):
        rows = (lengths == length).nonzero().flatten().tolist()  # the DP's rows of this length, in its order
        constant = list(range(args.constant - 1, length - 1, args.constant))
        for label, positions in zip(totals, ([dp_positions[i] for i in rows], [truth[i] for i in rows],
                                             [constant] * len(rows))):
            totals[label].append(path_cost(costs, positions))
    summed = {label: torch.cat(parts) for label, parts in totals.items()}  # (B,) per clip, by length
    fits = torch.stack(list(summed.values())).isfinite().all(0)
    if fits.any():
        truth_total, constant_total = summed["ground truth"][fits], summed[f"constant {args.constant}"][fits]
        print(f"\n| segmentation | mean summed {name} ({args.space}), {int(fits.sum())} clips |")
        print("|---|---|")
        for label, values in summed.items():
            print(f"| {label} | {values[fits].mean():.1f} |")
        print(f"\nThe labels cost less than Constant every {args.constant} frames on "
              f"{(truth_total < constant_total).float().mean():.1%} of these clips.")
    else:
        print(f"\nNo clip fits all three segmentations (each has a gap over S somewhere): no summed {name} to compare.")
    scores = column_scores(dp_positions, truth, lengths.tolist(), n_future)
    print(f"\nDP keyframes vs ground truth ({len(lengths)} clips; interior / with ends):")
    for column in ("interior", "with_ends"):
        print(f"- {column}: F1 {scores['f1_' + column]:.3f}, ±1 {scores['f1_tol1_' + column]:.3f}, "
              f"precision {scores['precision_' + column]:.3f}, recall {scores['recall_' + column]:.3f}, "
              f"{scores['n_predicted_' + column]:.2f} keyframes/clip")


if __name__ == "__main__":
    main()
