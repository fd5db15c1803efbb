"""What a stage-1 checkpoint draws: true frames above their auto-encoded reconstructions.

    python studies/stage1_reconstructions.py runs/<run>/checkpoints/interpolator/last.ckpt \
        --split val --clips 4 --every 5 --out docs/img/<name>.png

Also prints the mean BCE per frame of the reconstructions, of the per-pixel mean image and the
floor (the entropy of the targets: BCE cannot go below it for non-binary pixels), so that the
excess over the floor says how much of the picture is still missing.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import torch
import torch.nn.functional as F

from keyin.data.clips import ShardClips
from keyin.data.hdf5 import split_files
from keyin.lit.checkpoints import load_checkpoint
from keyin.lit.registry import load_trained_module


def frame_bce(probs: torch.Tensor, targets: torch.Tensor) -> float:
    """Mean over frames of the BCE summed over pixels, (F, C, H, W) each."""
    return float(F.binary_cross_entropy(probs.clamp(1e-6, 1 - 1e-6), targets, reduction="sum")) / len(targets)


@torch.no_grad()
def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("ckpt")
    parser.add_argument("--split", default="val")
    parser.add_argument("--data-dir", default="data")
    parser.add_argument("--clips", type=int, default=4)
    parser.add_argument("--every", type=int, default=5, help="show every n-th frame")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    module, config = load_trained_module(args.ckpt, "interpolator")
    hp = module.hparams
    clips = ShardClips(split_files(Path(args.data_dir) / config["dataset"]["name"], args.split),
                       (hp.image_size, hp.image_size, hp.channels), hp.n_cond, hp.n_future)
    frames = torch.stack([clips[i]["frames"] for i in range(args.clips)])  # (B, L, C, H, W)
    drawn = torch.sigmoid(module.decoder(module.encoder(frames)))
    flat, flat_drawn = frames.flatten(0, 1), drawn.flatten(0, 1)
    mean_image = flat.mean(0, keepdim=True).expand_as(flat)
    step = load_checkpoint(args.ckpt, "interpolator")["global_step"]
    print(f"step {step}: BCE per frame, reconstruction "
          f"{frame_bce(flat_drawn, flat):.1f}, mean image {frame_bce(mean_image, flat):.1f}, floor {frame_bce(flat, flat):.1f}")
    rows = [np.concatenate(list(video[:: args.every].permute(0, 2, 3, 1).numpy()), axis=1)
            for clip in range(args.clips) for video in (frames[clip], drawn[clip])]
    picture = (np.concatenate(rows, axis=0) * 255).round().astype(np.uint8)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(args.out, np.kron(picture, np.ones((2, 2, 1), dtype=np.uint8)))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
