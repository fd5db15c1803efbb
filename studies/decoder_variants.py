"""Exact and inexact ways to run the frame decoder faster on a CPU, on the segment costs' workload.

    python studies/decoder_variants.py --ckpt pretrained:brownian --frames 4096 --threads 1 \
        --out studies/results/decoder_variants.md

The decoder is 90 % of the exact segmentation's time (studies/results/map_cost_profile.md). Each
variant decodes the same random embeddings; its time is the best of ``--repeats`` after one warm-up
call, its largest logit difference is against the plain path:

- plain: the upsampling as training runs it (coordinate planes concatenated to every frame's
  features, contiguous feature maps): ``ConvDecoder._upsample``;
- eval: ``ConvDecoder.forward`` in eval mode, the default for inference and for the frozen decoder of
  stage 2 since 2026-12-05 (feature maps in ``channels_last``, each conv's response to the coordinate
  planes added as a bias computed once per call);
- eval, bf16 autocast: ``torch.autocast("cpu", torch.bfloat16)`` around it (inexact).
"""

from __future__ import annotations

import argparse
import sys
import time
from datetime import date
from pathlib import Path
from typing import Callable

import torch
from torch import Tensor

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # common.py stays with the benchmarks
from common import cpu_model, publish  # noqa: E402
from keyin.lit.registry import load_trained_module  # noqa: E402


def best_time(run: Callable[[], Tensor], repeats: int) -> float:
    run()
    times = []
    for _ in range(repeats):
        began = time.perf_counter()
        run()
        times.append(time.perf_counter() - began)
    return min(times)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--ckpt", default="pretrained:brownian")
    parser.add_argument("--frames", type=int, default=4096)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    torch.manual_seed(0)
    module, _ = load_trained_module(args.ckpt)
    decoder = module.model.decoder.eval()
    if decoder.skips:
        parser.error(f"{args.ckpt}'s decoder has skips: its eval path is the plain one")
    embeddings = torch.randn(args.frames, decoder.head[0].in_channels)
    rows = ["| variant | seconds | ms / frame | speed-up | largest logit difference |", "|---|---|---|---|---|"]
    with torch.inference_mode():

        def plain() -> Tensor:
            return decoder._upsample(decoder.head(embeddings.reshape(*embeddings.shape, 1, 1)), None)

        def bf16() -> Tensor:
            with torch.autocast("cpu", dtype=torch.bfloat16):
                return decoder(embeddings).float()

        reference = plain()
        variants = {"plain": plain, "eval": lambda: decoder(embeddings), "eval, bf16 autocast": bf16}
        first = None
        for name, run in variants.items():
            seconds = best_time(run, args.repeats)
            first = first or seconds
            difference = (run().float() - reference).abs().max().item()
            rows.append(f"| {name} | {seconds:.3f} | {1000 * seconds / args.frames:.3f} | {first / seconds:.2f}x | {difference:.2g} |")
    publish("\n".join([
        f"## The frame decoder's variants on {args.frames} embeddings ({args.ckpt})\n",
        f"- command: `python studies/decoder_variants.py --ckpt {args.ckpt} --frames {args.frames} --threads {args.threads} --repeats {args.repeats}`",
        f"- machine: {cpu_model()}, {args.threads} thread(s), torch {torch.__version__}, {date.today()}\n",
        *rows,
    ]), args.out)


if __name__ == "__main__":
    main()
