"""Does a pushing frame model draw the puck and the pusher where they are? Object scores by colour.

    python studies/stage1_objects.py <frames, stage-1 or stage-2 checkpoint> --split val --clips 200

The stage-1 gate of issue 25 in numbers: on validation clips, the frames the checkpoint's decoder
draws (a) auto-encoded and, where it has an interpolator, (b) interpolated between the true
keyframes (z = 0, every labelled segment of at most S frames), each object found by its flat colour
(:mod:`keyin.eval.placement`). Per object: how often the drawing shows it where the truth does, the
mean and median distance in pixels between the two centroids where both do, the share of frames
drawn within 2 px, and the IoU of the two colour masks. Prints Markdown.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import torch

from keyin.data.clips import ShardClips
from keyin.data.hdf5 import split_files
from keyin.data.segments import segment_frames, valid_frames
from keyin.eval.placement import placement_scores
from keyin.lit.checkpoints import STAGE_KEY, load_checkpoint
from keyin.lit.registry import load_trained_module
from keyin.models.interpolator import interpolate_segments


def frame_model(module: torch.nn.Module, stage: str) -> tuple[torch.nn.Module, torch.nn.Module, torch.nn.Module | None]:
    """The encoder, decoder and (None for a frame autoencoder) interpolator of a trained module."""
    if stage == "frames":
        return module.network.encoder, module.network.decoder, None
    networks = module.model if stage == "keyframes" else module
    return networks.encoder, networks.decoder, networks.interpolator


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
    checkpoint = load_checkpoint(args.ckpt)
    stage = checkpoint[STAGE_KEY]
    module, config = load_trained_module(args.ckpt, stage)
    encoder, decoder, interpolator = frame_model(module, stage)
    dataset = config["dataset"]
    n_cond, n_future = dataset["n_cond"], dataset["n_future"]
    clips = ShardClips(split_files(Path(args.data_dir) / dataset["name"], args.split),
                       (dataset["image_size"], dataset["image_size"], dataset["channels"]), n_cond, n_future)
    batch = [clips[i] for i in range(min(args.clips, len(clips)))]
    frames = torch.stack([item["frames"] for item in batch])  # (B, L, C, H, W)
    lengths = n_cond + torch.stack([item["future_length"] for item in batch])
    keyframes = torch.stack([item["keyframes"] for item in batch])  # (B, N)
    embeddings = encoder(frames)  # (B, L, E)
    valid = valid_frames(lengths, frames.shape[1])
    drawings = {"auto-encoded": (torch.sigmoid(decoder(embeddings[valid])), frames[valid])}
    if interpolator is not None:
        segments = labelled_segments(keyframes, lengths, n_cond, interpolator.max_offset)
        predicted, inside, _ = interpolate_segments(interpolator, None, embeddings, *segments, "mean")
        clip, start, offset = segments
        positions, _ = segment_frames(start, offset, interpolator.max_offset)
        truth = frames[clip[:, None].expand_as(positions)[inside], positions[inside]]
        drawings["interpolated"] = (torch.sigmoid(decoder(predicted[inside])), truth)
    print(f"## Where the frame model draws the objects: {args.ckpt} ({stage}, step {checkpoint['global_step']})\n")
    print(f"- command: `python studies/stage1_objects.py {args.ckpt} --split {args.split} --clips {len(batch)}`")
    print(f"- {', '.join(f'{len(drawn)} {name} frames' for name, (drawn, _) in drawings.items())}"
          f"{' (between the true keyframes, z = 0)' if interpolator is not None else ''}\n")
    print("| frames | object | drawn where the truth shows it | centroid error (px, where both) | median | within 2 px | mask IoU |")
    print("|---|---|---|---|---|---|---|")
    for name, (drawn, truth) in drawings.items():
        for obj, score in placement_scores(drawn, truth).items():
            print(f"| {name} | {obj} | {100 * score.drawn:.1f} % | {score.centroid_error_px:.2f} | "
                  f"{score.median_error_px:.2f} | {100 * score.within_2px:.1f} % | {score.iou:.3f} |")
    print(f"\n{time.perf_counter() - began:.0f} s, torch {torch.__version__}")


if __name__ == "__main__":
    main()
