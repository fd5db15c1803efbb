"""Does a pushing stage 1 draw the puck and the pusher where they are? Centroid errors by colour.

    python benchmarks/stage1_objects.py <stage-1 or stage-2 checkpoint> --split val --clips 200

The stage-1 gate of issue 25 in numbers: on validation clips, the frames the checkpoint's decoder
draws (a) auto-encoded and (b) interpolated between the true keyframes (z = 0, every labelled
segment of at most S frames), with each object found by its flat colour
(:func:`keyin.envs.segmentation.puck_centroid` with the scene's colours). Per object: how often it
is visible in the drawing where it is visible in the truth, and the mean distance in pixels between
the two centroids where both are. Prints Markdown.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
import torch

from keyin.data.clips import ShardClips
from keyin.data.hdf5 import split_files
from keyin.data.segments import segment_frames, valid_frames
from keyin.envs.pushing import COLOURS
from keyin.envs.segmentation import puck_centroid
from keyin.lit.checkpoints import load_checkpoint, load_trained_module
from keyin.models.interpolator import interpolate_segments

OBJECTS = ("puck", "pusher")


def object_errors(drawn: np.ndarray, truth: np.ndarray) -> dict[str, tuple[float, float]]:
    """Per object, (share of truth-visible frames where the drawing shows it, mean centroid error in px).

    Args:
        drawn, truth: (F, H, W, 3) float in [0, 1].
    """
    errors = {}
    for name in OBJECTS:
        drawn_at, _ = puck_centroid(drawn, COLOURS[name])
        true_at, _ = puck_centroid(truth, COLOURS[name])
        seen = ~np.isnan(true_at[:, 0])
        both = seen & ~np.isnan(drawn_at[:, 0])
        distance = np.linalg.norm(drawn_at[both] - true_at[both], axis=-1)
        errors[name] = (both.sum() / max(seen.sum(), 1), float(distance.mean()) if both.any() else float("nan"))
    return errors


def labelled_segments(keyframes: torch.Tensor, lengths: torch.Tensor, n_cond: int, max_offset: int) -> tuple[torch.Tensor, ...]:
    """clip, start, offset (R,) of the segments between consecutive labelled keyframes (clip axis),
    from the last conditioning frame, of at most ``max_offset`` frames."""
    clips, starts, offsets = [], [], []
    for clip, (row, length) in enumerate(zip(keyframes.tolist(), lengths.tolist())):
        bounds = [n_cond - 1] + [n_cond + p for p, key in enumerate(row) if key and n_cond + p < length]
        for left, right in zip(bounds[:-1], bounds[1:]):
            if right - left <= max_offset:
                clips.append(clip), starts.append(left), offsets.append(right - left)
    return torch.tensor(clips), torch.tensor(starts), torch.tensor(offsets)


@torch.no_grad()
def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("ckpt")
    parser.add_argument("--split", default="val")
    parser.add_argument("--data-dir", default="data")
    parser.add_argument("--clips", type=int, default=200)
    args = parser.parse_args()
    began = time.perf_counter()
    module, config = load_trained_module(args.ckpt, "interpolator")
    hp = module.hparams
    step = load_checkpoint(args.ckpt, "interpolator")["global_step"]
    clips = ShardClips(split_files(Path(args.data_dir) / config["dataset"]["name"], args.split),
                       (hp.image_size, hp.image_size, hp.channels), hp.n_cond, hp.n_future)
    batch = [clips[i] for i in range(min(args.clips, len(clips)))]
    frames = torch.stack([item["frames"] for item in batch])  # (B, L, C, H, W)
    lengths = hp.n_cond + torch.stack([item["future_length"] for item in batch])
    keyframes = torch.stack([item["keyframes"] for item in batch])  # (B, N)
    embeddings = module.encoder(frames)  # (B, L, E)
    valid = valid_frames(lengths, frames.shape[1])
    auto = torch.sigmoid(module.decoder(embeddings[valid])).permute(0, 2, 3, 1).numpy()
    truth = frames[valid].permute(0, 2, 3, 1).numpy()
    segments = labelled_segments(keyframes, lengths, hp.n_cond, hp.max_offset)
    predicted, inside, _ = interpolate_segments(module.interpolator, None, embeddings, *segments, "mean")
    clip, start, offset = segments
    positions, _ = segment_frames(start, offset, hp.max_offset)
    inter = torch.sigmoid(module.decoder(predicted[inside])).permute(0, 2, 3, 1).numpy()
    inter_truth = frames[clip[:, None].expand_as(positions)[inside], positions[inside]].permute(0, 2, 3, 1).numpy()
    print(f"## Where stage 1 draws the objects: {args.ckpt} (step {step})\n")
    print(f"- command: `python benchmarks/stage1_objects.py {args.ckpt} --split {args.split} --clips {len(batch)}`")
    print(f"- {len(truth)} auto-encoded frames, {len(inter)} frames interpolated between the true keyframes (z = 0)\n")
    print("| frames | object | visible where the truth shows it | centroid error (px, where both visible) |")
    print("|---|---|---|---|")
    for name, (drawn, target) in {"auto-encoded": (auto, truth), "interpolated": (inter, inter_truth)}.items():
        for obj, (seen, error) in object_errors(drawn, target).items():
            print(f"| {name} | {obj} | {100 * seen:.1f} % | {error:.2f} |")
    print(f"\n{time.perf_counter() - began:.0f} s, torch {torch.__version__}")


if __name__ == "__main__":
    main()
