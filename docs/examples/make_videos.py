"""Ten mp4 videos of Structured Brownian motion written by PyAV (not by keyin), and their turns as a
labels CSV: the input of the "Your own videos" walk-through in docs/discover.md (docs/examples/own_videos.sh).

    python docs/examples/make_videos.py <folder>
"""

from __future__ import annotations

import csv
import sys
from pathlib import Path

import av
import numpy as np

from keyin.data.brownian import BrownianGenerator

FPS = 20
FRAMES = 240  # each video: 12 s


def write_mp4(path: Path, frames: np.ndarray) -> None:
    """(T, H, W) uint8 grey frames as an H.264 mp4 at 4x size (a camera's video is larger than the model's)."""
    big = frames.repeat(4, axis=1).repeat(4, axis=2)
    with av.open(str(path), "w") as container:
        stream = container.add_stream("libx264", rate=FPS)
        stream.width, stream.height, stream.pix_fmt = big.shape[2], big.shape[1], "yuv420p"
        for frame in big:
            container.mux(stream.encode(av.VideoFrame.from_ndarray(np.repeat(frame[..., None], 3, -1), format="rgb24")))
        container.mux(stream.encode())


def main(folder: Path) -> None:
    (folder / "my_videos").mkdir(parents=True, exist_ok=True)
    generator = BrownianGenerator(n_cond=1, n_future=FRAMES - 1)
    with open(folder / "labels.csv", "w", newline="") as out:
        labels = csv.writer(out)
        labels.writerow(["video", "frame"])
        for index in range(10):
            arrays, _ = generator.generate(index, seed=2026)
            write_mp4(folder / "my_videos" / f"run{index:02d}.mp4", arrays["frames"][..., 0])
            labels.writerows([f"run{index:02d}.mp4", int(frame)] for frame in arrays["keyframes"].nonzero()[0])


if __name__ == "__main__":
    main(Path(sys.argv[1]))
