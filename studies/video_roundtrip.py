"""Test clips through a video file and back: do a trained model's keyframes survive the codec?

    python studies/video_roundtrip.py pretrained:brownian --data data/brownian/test-00000.h5 --clips 200 [--codec ffv1]

Each of the first ``--clips`` clips of a keyin HDF5 shard (its valid frames only) is written as a
video by a video library (imageio's PyAV plugin, 10 frames per second; ``--codec h264``: an mp4 at
H.264's default quality, lossy as a camera's; ``--codec ffv1``: a lossless FFV1 mkv, which isolates
the import pipeline from the codec), with its labelled keyframes as a labels file; ``keyin-import``
reads them back as a user's videos are read (one clip per video, padded like the original), and the
checkpoint's discovery rule finds keyframes on both the original and the re-imported clips. Prints
Markdown: the frames' error after the codec, F1 on both (interior column), how many clips get the
same keyframes, and the mean distance between the two sets where they differ.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import imageio.v3 as iio
import numpy as np
import torch
from torch.utils.data import Subset

from keyin.data.clips import ShardClips
from keyin.data.hdf5 import load_arrays, split_files
from keyin.data.imports import clip_origins
from keyin.eval.discovery import discover
from keyin.eval.f1 import hausdorff
from keyin.lit.registry import load_trained_module

FPS = 10
CODECS = {  # name -> (FFmpeg encoder, its pixel format or None for the default, file suffix, description)
    "h264": ("libx264", None, ".mp4", "H.264 mp4 (default quality)"),
    "ffv1": ("ffv1", "bgr0", ".mkv", "FFV1 mkv (lossless)"),
}


def write_videos(arrays: dict[str, np.ndarray], count: int, folder: Path, codec: str) -> dict[str, list[int]]:
    """``clip0000<suffix>`` … with each clip's valid frames; returns the labels (clip-axis frame indices)."""
    encoder, pixel_format, suffix, _ = CODECS[codec]
    folder.mkdir(parents=True, exist_ok=True)
    labels = {}
    for index in range(count):
        frames = arrays["frames"][index, : int(arrays["length"][index])]  # (T, H, W, C) uint8
        if frames.shape[-1] == 1:
            frames = np.repeat(frames, 3, axis=-1)
        name = f"clip{index:04d}{suffix}"
        iio.imwrite(folder / name, frames, plugin="pyav", codec=encoder, fps=FPS, out_pixel_format=pixel_format)
        labels[name] = np.flatnonzero(arrays["keyframes"][index]).tolist()
    return labels


def import_videos(videos: Path, labels: Path, data_dir: Path, dataset: dict) -> Path:
    """Run ``keyin-import`` as a user would; returns the imported test shard folder."""
    overrides = [f"dataset.{key}={dataset[key]}" for key in ("image_size", "channels", "n_cond", "n_future", "n_keyframes", "max_offset")]
    command = [
        sys.executable, "-m", "keyin.cli.import_videos", f"source={videos}", f"labels={labels}", f"data_dir={data_dir}",
        "dataset=custom", *overrides, "fractions={train: 0, val: 0, test: 1.0}", f"fps={FPS}", "progress=false", f"hydra.run.dir={data_dir}/run",
    ]
    done = subprocess.run(command, capture_output=True, text=True)
    if done.returncode:
        sys.exit(f"keyin-import failed:\n{done.stdout[-2000:]}{done.stderr[-2000:]}")
    return data_dir / "custom"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("ckpt", help="a stage-2 checkpoint or pretrained:<name>")
    parser.add_argument("--data", type=Path, required=True, help="a keyin HDF5 shard (e.g. data/pushing/test-00000.h5)")
    parser.add_argument("--clips", type=int, default=200)
    parser.add_argument("--rule", default=None, help="the discovery rule (default: the checkpoint's own)")
    parser.add_argument("--codec", choices=sorted(CODECS), default="h264", help="the video codec the clips go through")
    args = parser.parse_args()
    began = time.perf_counter()
    module, config = load_trained_module(args.ckpt)
    dataset = config["dataset"]
    rule = args.rule or module.discovery
    find = module.discoverers("model", [rule])
    (discoverer,) = find.values()
    arrays = load_arrays(args.data)
    count = min(args.clips, len(arrays["length"]))
    shape = (dataset["image_size"], dataset["image_size"], dataset["channels"])
    original = discover(discoverer, Subset(ShardClips([args.data], shape, dataset["n_cond"], dataset["n_future"]), range(count)))
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        labels = write_videos(arrays, count, work / "videos", args.codec)
        (work / "labels.json").write_text(json.dumps(labels))
        folder = import_videos(work / "videos", work / "labels.json", work / "data", dataset)
        files = split_files(folder, "test")
        imported_clips = ShardClips(files, shape, dataset["n_cond"], dataset["n_future"])
        order = [int(Path(origin.video).stem.removeprefix("clip")) for origin in clip_origins(folder, "test")]
        imported = discover(discoverer, imported_clips)
        decoded = np.concatenate([load_arrays(path, ("frames",))["frames"] for path in files])
    by_clip = {clip: row for row, clip in enumerate(order)}
    rows = [by_clip[clip] for clip in range(count)]
    error = np.mean([
        np.abs(decoded[row, : int(arrays["length"][clip])].astype(float) - arrays["frames"][clip, : int(arrays["length"][clip])]).mean()
        for clip, row in zip(range(count), rows)
    ])
    imported.predicted = [imported.predicted[row] for row in rows]
    imported.truth = [imported.truth[row] for row in rows]
    imported.lengths = [imported.lengths[row] for row in rows]
    n_future = dataset["n_future"]
    same = sum(a == b for a, b in zip(original.predicted, imported.predicted))
    differing = [hausdorff(a, b, n_future) for a, b in zip(original.predicted, imported.predicted) if a != b]
    scores = {name: found.scores(n_future) for name, found in (("original", original), ("imported", imported))}
    description = CODECS[args.codec][3]
    print(f"## Keyframes through a video file and back ({args.data}, {description})\n")
    print(f"- command: `python studies/video_roundtrip.py {args.ckpt} --data {args.data} --clips {args.clips} --codec {args.codec}`; rule `{rule}`")
    print(f"- {count} clips as {description} (imageio + PyAV, {FPS} fps), re-imported by keyin-import")
    print(f"- the frames after the codec: mean absolute error {error:.2f} of 255\n")
    print("| clips | F1 interior | ±1 F1 interior | F1 as given | keyframes/clip |")
    print("|---|---|---|---|---|")
    for name, score in scores.items():
        print(f"| {name} | {score['f1_interior']:.3f} | {score['f1_tol1_interior']:.3f} | {score['f1']:.3f} | {score['n_predicted']:.2f} |")
    mean_distance = f"{np.mean(differing):.2f}" if differing else "–"
    print(f"\nSame keyframes on {same} of {count} clips; where they differ, mean Hausdorff distance {mean_distance} frames.")
    print(f"\n{time.perf_counter() - began:.0f} s, torch {torch.__version__}")


if __name__ == "__main__":
    main()
