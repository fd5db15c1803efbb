"""Where TAP's subgoal predictions land in time: the chosen frame of each clip's (first, last) pair.

    python studies/tap_landing.py runs/<tap run>/checkpoints/tap/last.ckpt --split test --clips 1000 \
        --out studies/results/tap_landing_<name>.md

The chosen frame is the admissible frame the prediction matches best under the minimum-over-time rule
of the checked-out keyin (keyin/losses/tap.py), so two checkpoints scored by one checkout are compared
by one rule. Reports the mean (t − a)/(b − a), the fraction in the middle third and per tenth.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from datetime import date
from pathlib import Path

import torch
from torch.utils.data import Subset

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # common.py stays with the benchmarks
from common import clip_arguments, cpu_model, publish  # noqa: E402
from keyin.data.clips import ShardClips  # noqa: E402
from keyin.data.hdf5 import split_files  # noqa: E402
from keyin.lit.registry import load_trained_module  # noqa: E402


def main() -> None:
    parser = clip_arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), clips=1000)
    parser.add_argument("ckpt", help="a TAP checkpoint (checkpoints/tap/last.ckpt)")
    args = parser.parse_args()
    module, config = load_trained_module(args.ckpt, "tap")
    dataset = config["dataset"]
    clips = ShardClips(split_files(Path(args.data_dir) / dataset["name"], args.split),
                       (dataset["image_size"], dataset["image_size"], dataset["channels"]), dataset["n_cond"], dataset["n_future"])
    clips = Subset(clips, range(min(args.clips, len(clips))))
    started = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder, torch.no_grad():
        scores = module.test_metrics(clips, Path(folder))
    seconds = time.perf_counter() - started
    deciles = " | ".join(f"{share:.3f}" for share in scores["argmin_deciles"])
    report = "\n".join([
        f"# Where TAP's predictions land: {args.ckpt}",
        "",
        f"`python studies/tap_landing.py {args.ckpt} --split {args.split} --clips {len(clips)}` ({cpu_model()}, "
        f"{date.today()}, {seconds:.1f} s; margin {module.hparams.margin}).",
        "",
        f"Mean (t − a)/(b − a) {scores['argmin_relative']:.3f}; middle third {scores['argmin_middle']:.3f}; "
        f"at the last admissible frame {scores['argmin_last']:.3f}; BCE per pixel {scores['bce_per_pixel']:.4f}.",
        "",
        "| tenth of the clip | " + " | ".join(f"{k / 10:.1f}-{(k + 1) / 10:.1f}" for k in range(10)) + " |",
        "|---|" + "---|" * 10,
        f"| share of clips | {deciles} |",
        "",
        "```json",
        json.dumps({"ckpt": str(args.ckpt), **scores}),
        "```",
    ])
    publish(report + "\n", args.out)


if __name__ == "__main__":
    main()
