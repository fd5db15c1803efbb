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

from common import clip_arguments, cpu_model, publish, split_batch
from keyin.decode.baselines import ConstantKeyframes
from keyin.eval.f1 import column_scores, keyframe_lists


def main() -> None:
    parser = clip_arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), clips=1000)
    parser.add_argument("--dataset", default="brownian")
    parser.add_argument("--first-m", action="store_true", help="every c in 1..S, the first M keyframes kept")
    args = parser.parse_args()
    dataset, batch = split_batch(args.dataset, args.split, args.clips, args.data_dir)
    truth, lengths = keyframe_lists(batch["keyframes"]), batch["future_length"].tolist()
    cap = dataset.n_keyframes if args.first_m else None
    smallest = 1 if args.first_m else dataset.n_future // (dataset.n_keyframes + 1) + 1  # else: ≤ M keyframes in a full clip
    scores = {
        offset: column_scores(ConstantKeyframes(offset, cap)(batch["frames"], batch["future_length"]), truth, lengths,
                              dataset.n_future)
        for offset in range(smallest, dataset.max_offset + 1)
    }
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
