"""The exact segmentation ("map") with the frame networks compiled (``compile=true`` of keyin-eval and
keyin-discover) against eager: seconds, compile time, and whether the keyframes are the same.

    python benchmarks/compile_inference.py --ckpt pretrained:brownian --clips 200 \
        --out benchmarks/results/compile_inference.md
"""

from __future__ import annotations

import argparse
import time
from datetime import date

import torch

from common import clip_arguments, cpu_model, publish, split_batch
from keyin.lit.registry import load_trained_module
from keyin.lit.run import compile_frame_networks


def discovered(module: torch.nn.Module, batch: dict, rule: str, batch_size: int) -> tuple[float, list[list[int]]]:
    started, found = time.perf_counter(), []
    for first in range(0, len(batch["frames"]), batch_size):
        part = slice(first, first + batch_size)
        found += module.discover(batch["frames"][part], batch["future_length"][part], discovery=rule)
    return time.perf_counter() - started, found


def main() -> None:
    parser = clip_arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), clips=200)
    parser.set_defaults(split="test")  # a speed measurement, no choice made
    parser.add_argument("--ckpt", default="pretrained:brownian")
    parser.add_argument("--rule", default="map")
    parser.add_argument("--batch-size", type=int, default=100)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    module, config = load_trained_module(args.ckpt)
    _, batch = split_batch(config["dataset"]["name"], args.split, args.clips, args.data_dir)
    eager_s, eager = discovered(module, batch, args.rule, args.batch_size)
    compile_frame_networks(module)
    first_s, _ = discovered(module, {k: v[: args.batch_size] for k, v in batch.items()}, args.rule, args.batch_size)
    compiled_s, compiled = discovered(module, batch, args.rule, args.batch_size)
    same = sum(a == b for a, b in zip(eager, compiled))
    report = "\n".join([
        f"## `compile=true` against eager: rule {args.rule}, {args.ckpt}, {len(eager)} {args.split} clips\n",
        f"- command: `python benchmarks/compile_inference.py --ckpt {args.ckpt} --clips {args.clips} --rule {args.rule} "
        f"--threads {args.threads}`",
        f"- machine: {cpu_model()}, torch {torch.__version__}, {args.threads} thread(s), {date.today()}\n",
        "| | seconds | clips / s |",
        "|---|---|---|",
        f"| eager | {eager_s:.1f} | {len(eager) / eager_s:.1f} |",
        f"| compiled (after compiling) | {compiled_s:.1f} | {len(eager) / compiled_s:.1f} |",
        f"| the first batch, compiling included | {first_s:.1f} | |\n",
        f"Speed-up {eager_s / compiled_s:.2f}x; the same keyframes on {same} of {len(eager)} clips.",
    ])
    publish(report, args.out)


if __name__ == "__main__":
    main()
