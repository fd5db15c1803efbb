"""Tiny synthetic videos in every source format keyin-import reads, written by the libraries
themselves (PyAV through imageio, Pillow, numpy, h5py), never by keyin.

Frame t of a video is one grey level, ``LEVEL0 + LEVEL_STEP * t`` (RGB, 24x32), so every imported
frame tells which original frame it is, through the lossy codecs too (:func:`frame_numbers`).
"""

from __future__ import annotations

import json
from pathlib import Path

import h5py
import imageio.v3 as iio
import numpy as np
import torch
from PIL import Image

LEVEL0, LEVEL_STEP = 10, 5
FPS = 10
EVENTS = [7, 16, 25, 33]  # the labelled keyframes of every synthetic video (original frame numbers)


def frames(n_frames: int = 40, height: int = 24, width: int = 32) -> np.ndarray:
    """(T, H, W, 3) uint8: frame t is grey level LEVEL0 + LEVEL_STEP * t."""
    levels = LEVEL0 + LEVEL_STEP * np.arange(n_frames)
    return np.broadcast_to(levels[:, None, None, None], (n_frames, height, width, 3)).astype(np.uint8)


def frame_numbers(clip: torch.Tensor) -> list[int]:
    """The original frame numbers of an item's (L, C, H, W) frames in [0, 1], read from their grey level."""
    means = clip.mean(dim=(1, 2, 3)).numpy() * 255
    return np.round((means - LEVEL0) / LEVEL_STEP).astype(int).tolist()


def write_video(path: Path, video: np.ndarray) -> Path:
    """A video file by PyAV (H.264 for .mp4/.avi, VP9 for .webm), a .gif by Pillow."""
    if path.suffix == ".gif":
        iio.imwrite(path, video, plugin="pillow", duration=1000 / FPS, loop=0)
    else:
        iio.imwrite(path, video, plugin="pyav", codec="libvpx-vp9" if path.suffix == ".webm" else "libx264", fps=FPS)
    return path


def write_png_folder(folder: Path, video: np.ndarray) -> Path:
    """One PNG per frame, named frame0.png … (unpadded, so name order alone would be wrong)."""
    folder.mkdir(parents=True)
    for index, frame in enumerate(video):
        Image.fromarray(frame).save(folder / f"frame{index}.png")
    return folder


def write_robomimic(path: Path, videos: list[np.ndarray], camera_key: str = "agentview_image") -> Path:
    """A robomimic-style file: data/demo_<i>/obs/<camera_key> (T, H, W, 3) uint8, plus actions."""
    with h5py.File(path, "w") as handle:
        for index, video in enumerate(videos):
            demo = handle.create_group(f"data/demo_{index}")
            demo["obs/" + camera_key] = video
            demo["obs/robot0_eef_pos"] = np.zeros((len(video), 3), np.float32)
            demo["actions"] = np.zeros((len(video), 7), np.float32)
    return path


LEROBOT_VIDEO_PATH = "videos/chunk-{episode_chunk:03d}/{video_key}/episode_{episode_index:06d}.mp4"


def write_lerobot(
    root: Path, cameras: dict[str, list[np.ndarray]], version: str = "v2.1", chunks_size: int = 2, fps: float = FPS
) -> Path:
    """A LeRobot v2 folder as its docs lay it out: meta/info.json (fps, chunks_size, the video_path
    template, the features), meta/episodes.jsonl, one H.264 mp4 per episode and camera (episodes of
    ``chunks_size`` per chunk folder, so a small set spans chunks; the mp4s at FPS, info.json at ``fps``);
    no parquet files, which keyin never reads."""
    n_episodes = len(next(iter(cameras.values())))
    features = {"action": {"dtype": "float32", "shape": [7], "names": None}}
    for key, videos in cameras.items():
        height, width = videos[0].shape[1:3]
        features[key] = {"dtype": "video", "shape": [height, width, 3], "names": ["height", "width", "channel"]}
        for index, video in enumerate(videos):
            path = root / LEROBOT_VIDEO_PATH.format(episode_chunk=index // chunks_size, video_key=key, episode_index=index)
            path.parent.mkdir(parents=True, exist_ok=True)
            write_video(path, video)
    info = {"codebase_version": version, "fps": fps, "chunks_size": chunks_size, "total_episodes": n_episodes,
            "data_path": "data/chunk-{episode_chunk:03d}/episode_{episode_index:06d}.parquet",
            "video_path": LEROBOT_VIDEO_PATH, "features": features}
    (root / "meta").mkdir(parents=True, exist_ok=True)
    (root / "meta" / "info.json").write_text(json.dumps(info, indent=4))
    lengths = [len(video) for video in next(iter(cameras.values()))]
    (root / "meta" / "episodes.jsonl").write_text("".join(
        json.dumps({"episode_index": i, "tasks": ["push the block"], "length": n}) + "\n" for i, n in enumerate(lengths)
    ))
    return root
