"""Where the exact segmentation's ("map") time goes: the interpolator, the decoder and the BCE over
every in-clip segment of a batch of clips, and how many frames it decodes per clip frame.

    python studies/map_cost_profile.py --ckpt pretrained:brownian --clips 32 \
        --out studies/results/map_cost_profile.md

The segment costs (:func:`keyin.decode.segment_costs.interpolation_costs`) decode, for every start a
and offset o ≤ S, the o frames between the two true boundary embeddings: Σ_o o ≈ S(S+1)/2 decoded
frames per start, so the decoder's cost per frame, times that count, bounds the rule's speed.
"""

from __future__ import annotations

import argparse
import sys
import time
from datetime import date
from pathlib import Path

import torch
import torch.nn.functional as F

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))  # common.py stays with the benchmarks
from common import clip_arguments, cpu_model, publish, split_batch  # noqa: E402
from keyin.data.segments import all_segments, segment_frames  # noqa: E402
from keyin.decode.segment_costs import interpolation_costs  # noqa: E402
from keyin.lit.registry import load_trained_module  # noqa: E402
from keyin.models.interpolator import interpolate_segments  # noqa: E402


def timed(step, repeats: int = 1) -> tuple[float, object]:
    started = time.perf_counter()
    for _ in range(repeats):
        out = step()
    return (time.perf_counter() - started) / repeats, out


@torch.no_grad()
def profile(model: torch.nn.Module, clips: torch.Tensor) -> dict[str, float]:
    """Seconds of each part of the segment costs of ``clips`` (B, L, C, H, W)."""
    n_cond, batch = model.n_cond, len(clips)
    n_future, max_offset = clips.shape[1] - n_cond, model.interpolator.max_offset
    encode, emb = timed(lambda: model.encoder(clips)[:, n_cond - 1:])
    frames = clips[:, n_cond:].flatten(2)
    total, _ = timed(lambda: interpolation_costs(model.interpolator, model.decoder, emb, frames))
    clip, start, offset = all_segments(batch, 0, n_future, range(1, max_offset + 1))
    interpolate, (predicted, valid, _) = timed(lambda: interpolate_segments(model.interpolator, None, emb, clip, start,
                                                                            offset, "mean"))
    positions = segment_frames(start, offset, max_offset)[0] - 1  # extended index k is future position k - 1
    outputs = predicted[valid]
    decode, logits = timed(lambda: torch.cat([model.decoder(part) for part in outputs.split(4096)]).flatten(1))
    rows = clip[:, None].expand_as(positions)[valid]
    targets = frames[rows, positions[valid]]
    bce, _ = timed(lambda: F.binary_cross_entropy_with_logits(logits, targets, reduction="none").sum(1))
    return {"clips": batch, "clip_frames": batch * n_future, "segments": len(clip), "decoded_frames": len(outputs),
            "encoder_s": encode, "costs_s": total, "interpolator_s": interpolate, "decoder_s": decode, "bce_s": bce}


def main() -> None:
    parser = clip_arguments(argparse.ArgumentParser(description=__doc__.splitlines()[0]), clips=32)
    parser.set_defaults(split="test")  # a speed measurement, no choice made
    parser.add_argument("--ckpt", default="pretrained:brownian")
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    args = parser.parse_args()
    module, config = load_trained_module(args.ckpt)
    _, batch = split_batch(config["dataset"]["name"], args.split, args.clips, args.data_dir)
    rows = []
    for threads in args.threads:
        torch.set_num_threads(threads)
        p = profile(module.model, batch["frames"])
        rows.append(
            f"| {threads} | {p['clips']} × {p['clip_frames'] // p['clips']} | {p['segments']} | {p['decoded_frames']} "
            f"({p['decoded_frames'] / p['clip_frames']:.1f} per clip frame) | {p['costs_s']:.2f} | {p['encoder_s']:.3f} | "
            f"{p['interpolator_s']:.2f} | {p['decoder_s']:.2f} ({1000 * p['decoder_s'] / p['decoded_frames']:.3f} ms/frame) | "
            f"{p['bce_s']:.2f} | {p['clip_frames'] / p['costs_s']:.0f} |"
        )
    report = "\n".join([
        f"## The exact segmentation's segment costs, part by part ({args.ckpt}, {args.clips} {args.split} clips)\n",
        f"- command: `python studies/map_cost_profile.py --ckpt {args.ckpt} --clips {args.clips} --split {args.split}`",
        f"- machine: {cpu_model()}, torch {torch.__version__}, {date.today()}\n",
        "| threads | clips × future frames | segments | decoded frames | costs (s) | encoder (s) | interpolator (s) "
        "| decoder (s) | BCE (s) | clip frames / s |",
        "|---|---|---|---|---|---|---|---|---|---|",
        *rows,
    ])
    publish(report, args.out)


if __name__ == "__main__":
    main()
