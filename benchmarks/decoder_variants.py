"""Exact and inexact ways to run the frame decoder faster on a CPU, on the segment costs' workload.

    python benchmarks/decoder_variants.py --ckpt pretrained:brownian --frames 4096 --threads 1 \
        --out benchmarks/results/decoder_variants.md

The decoder is 90 % of the exact segmentation's time (benchmarks/results/map_cost_profile.md). Each
variant decodes the same random embeddings; its time is the best of ``--repeats`` after one warm-up
call, its largest logit difference is against the eager float32 decoder:

- eager: ``ConvDecoder.forward`` as trained;
- channels_last: the decoder's weights in ``torch.channels_last``;
- bf16 autocast: ``torch.autocast("cpu", torch.bfloat16)`` (inexact);
- coordinate bias: the coordinate channels' share of each transposed convolution computed once per
  resolution and added, instead of concatenated to every frame's features (exact up to rounding).
"""

from __future__ import annotations

import argparse
import time
from datetime import date
from pathlib import Path
from typing import Callable

import torch
import torch.nn.functional as F
from torch import Tensor

from common import cpu_model, publish
from keyin.lit.registry import load_trained_module
from keyin.models.conv import ConvDecoder, coordinate_planes


def coordinate_bias_decode(decoder: ConvDecoder, embeddings: Tensor) -> Tensor:
    """``decoder(embeddings)`` with each block's coordinate planes convolved once, not per frame
    (a decoder with ``coord_channels`` and no skips)."""
    features = decoder.head(embeddings.reshape(-1, embeddings.shape[-1], 1, 1))
    for block in decoder.upsampling:
        conv, channels = block[0], features.shape[1]
        planes = coordinate_planes(features.shape[-1], features)  # (1, 2, h, h)
        shared = F.conv_transpose2d(planes, conv.weight[channels:], None, conv.stride, conv.padding)
        features = F.conv_transpose2d(features, conv.weight[:channels], conv.bias, conv.stride, conv.padding) + shared
        for layer in block[1:]:
            features = layer(features)
    return features


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
    if not decoder.coord_channels or decoder.skips:
        parser.error(f"{args.ckpt}'s decoder has no coordinate channels or has skips: the coordinate bias does not apply")
    embeddings = torch.randn(args.frames, decoder.head[0].in_channels)
    rows = ["| variant | seconds | ms / frame | speed-up | largest logit difference |", "|---|---|---|---|---|"]
    with torch.inference_mode():
        reference = decoder(embeddings)

        def bf16() -> Tensor:
            with torch.autocast("cpu", dtype=torch.bfloat16):
                return decoder(embeddings).float()

        variants = {
            "eager": lambda: decoder(embeddings),
            "coordinate bias": lambda: coordinate_bias_decode(decoder, embeddings),
            "bf16 autocast": bf16,
        }
        eager = None
        for name, run in variants.items():
            seconds = best_time(run, args.repeats)
            eager = eager or seconds
            difference = (run().float() - reference).abs().max().item()
            rows.append(f"| {name} | {seconds:.3f} | {1000 * seconds / args.frames:.3f} | {eager / seconds:.2f}x | {difference:.2g} |")
        decoder.to(memory_format=torch.channels_last)  # last: it changes the decoder in place
        seconds = best_time(lambda: decoder(embeddings), args.repeats)
        difference = (decoder(embeddings) - reference).abs().max().item()
        rows.append(f"| channels_last | {seconds:.3f} | {1000 * seconds / args.frames:.3f} | {eager / seconds:.2f}x | {difference:.2g} |")
    publish("\n".join([
        f"## The frame decoder's variants on {args.frames} embeddings ({args.ckpt})\n",
        f"- command: `python benchmarks/decoder_variants.py --ckpt {args.ckpt} --frames {args.frames} --threads {args.threads} --repeats {args.repeats}`",
        f"- machine: {cpu_model()}, {args.threads} thread(s), torch {torch.__version__}, {date.today()}\n",
        *rows,
    ]), args.out)


if __name__ == "__main__":
    main()
