"""Choose the Constant baseline's spacing c on validation clips.

    python benchmarks/choose_constant.py --dataset pushing --clips 1000 \
        --out benchmarks/results/choose_constant_pushing.md

Constant marks every c-th future frame (keyin/decode/baselines.py); every c in 1..S that places at
most M keyframes in a full clip (as every method may) is scored on the validation split by interior
F1 (docs/evaluation.md), and the best is ``dataset.tuned.constant_offset``. Validation clips only: the test split stays for the reported F1.
With ``--first-m`` every c in 1..S is scored keeping the first M keyframes of each clip (Jumpy's fixed
pattern without its training): the strongest fixed pattern, reported beside the table's Constant.
"""

from __future__ import annotations

import argparse
from datetime import date

import torch

from common import clip_arguments, cpu_model, publish, split_batch
from keyin.decode.baselines import ConstantKeyframes
from keyin.eval.f1 import column_scores, keyframe_lists


def pattern_scores(
    keyframes: torch.Tensor, future_length: torch.Tensor, n_keyframes: int, max_offset: int, first_m: bool
) -> dict[int, dict[str, float]]:
    """Each spacing c's scores (keyin.eval.f1.column_scores) against (B, N) labelled ``keyframes``: every c
    in 1..S with the first M keyframes kept when ``first_m``, else the c that put at most M in a full clip."""
    n_future = keyframes.shape[1]
    truth, lengths = keyframe_lists(keyframes), future_length.tolist()
    smallest = 1 if first_m else n_future // (n_keyframes + 1) + 1
    cap = n_keyframes if first_m else None
    return {c: column_scores(ConstantKeyframes(c, cap)(None, future_length), truth, lengths, n_future)
            for c in range(smallest, max_offset + 1)}


def main() -> None:
    parser = clip_arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), clips=1000)
    parser.add_argument("--dataset", default="brownian")
    parser.add_argument("--first-m", action="store_true", help="every c in 1..S, the first M keyframes kept")
    args = parser.parse_args()
    dataset, batch = split_batch(args.dataset, args.split, args.clips, args.data_dir)
    scores = pattern_scores(batch["keyframes"], batch["future_length"], dataset.n_keyframes, dataset.max_offset,
                            args.first_m)
    best = max(scores, key=lambda offset: scores[offset]["f1_interior"])
    rows = ["| c | F1 interior | ±1 F1 interior | F1 with ends | keyframes/clip (interior) |", "|---|---|---|---|---|"]
    for offset, s in scores.items():
        mark = "**" if offset == best else ""
        rows.append(f"| {offset} | {mark}{s['f1_interior']:.3f}{mark} | {s['f1_tol1_interior']:.3f} | {s['f1_with_ends']:.3f} | "
                    f"{s['n_predicted_interior']:.2f} |")
    report = "\n".join([
        f"## Constant baseline{', the first M kept' if args.first_m else ''}: its spacing c on {len(batch['frames'])} "
        f"{args.split} clips ({args.dataset})\n",
        f"- command: `python benchmarks/choose_constant.py --dataset {args.dataset} --clips {args.clips} --split {args.split}"
        f"{' --first-m' if args.first_m else ''}`",
        f"- machine: {cpu_model()}, {date.today()}; best c = {best} (interior F1 {scores[best]['f1_interior']:.3f})\n",
        *rows,
    ])
    publish(report, args.out)


if __name__ == "__main__":
    main()
