"""Pictures of discovered keyframes: a PNG strip per clip and an animated GIF, borders marking them.

Border colours: green = a ground-truth keyframe only, red = a predicted keyframe only, yellow =
both (a hit); conditioning frames get a grey border.
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import imageio.v3 as iio
import numpy as np
import torch

TRUE, PREDICTED, HIT, CONDITION = (0, 200, 0), (220, 0, 0), (240, 200, 0), (110, 110, 110)


def marked_frames(
    frames: torch.Tensor, n_cond: int, truth: Sequence[int], predicted: Sequence[int], border: int = 2
) -> np.ndarray:
    """Each frame of one clip as RGB with a coloured border.

    Args:
        frames: (L, C, H, W) in [0, 1], C = 1 or 3.
        n_cond: conditioning frames at the start of the clip.
        truth, predicted: future indices (0 = the first frame after the conditioning ones).
    Returns:
        (L, H + 2·border, W + 2·border, 3) uint8.
    """
    images = (frames.clamp(0, 1) * 255).round().to(torch.uint8).permute(0, 2, 3, 1).cpu().numpy()
    if images.shape[-1] == 1:
        images = np.repeat(images, 3, axis=-1)
    padded = np.pad(images, ((0, 0), (border, border), (border, border), (0, 0)))
    for index in range(len(padded)):
        future = index - n_cond
        colour = CONDITION if future < 0 else None
        if future in truth and future in predicted:
            colour = HIT
        elif future in truth:
            colour = TRUE
        elif future in predicted:
            colour = PREDICTED
        if colour is not None:
            inner = padded[index, border:-border, border:-border].copy()
            padded[index, :, :] = colour
            padded[index, border:-border, border:-border] = inner
    return padded


def save_keyframe_gif(
    path: Path, rows: np.ndarray, per_column: int = 1, duration_ms: float = 250, side: int = 256
) -> Path:
    """An animated GIF of marked clips, one frame per clip index: the clips side by side, or in
    columns of ``per_column`` consecutive clips, enlarged by a whole factor to about ``side``
    pixels high per clip.

    Args:
        rows: (K, L, h, w, 3) uint8, e.g. :func:`marked_frames` of each clip; K divisible by
            ``per_column``.
        duration_ms: how long each frame shows.
    """
    n_clips, length, height, width, _ = rows.shape
    columns = rows.reshape(n_clips // per_column, per_column, length, height, width, 3)
    movie = columns.transpose(2, 1, 3, 0, 4, 5).reshape(length, per_column * height, -1, 3)
    scale = max(1, side // height)
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(path, movie.repeat(scale, axis=1).repeat(scale, axis=2), duration=duration_ms, loop=0)
    return path


def save_keyframe_pictures(
    folder: Path,
    clips: torch.Tensor,
    n_cond: int,
    truth: Sequence[Sequence[int]],
    predicted: Sequence[Sequence[int]],
    name: str = "keyframes",
    per_column: int = 1,
) -> tuple[Path, Path]:
    """Write ``<name>.png`` (one row per clip, frames left to right) and ``<name>.gif``
    (:func:`save_keyframe_gif`).

    Args:
        clips: (K, L, C, H, W) in [0, 1].
        truth, predicted: per clip, future keyframe indices.
        per_column: the GIF stacks this many consecutive clips in each column (K divisible by it),
            e.g. 3 for the truth, reconstruction and sample of one clip.
    Returns:
        The PNG and GIF paths.
    """
    rows = np.stack(
        [marked_frames(clip, n_cond, t, p) for clip, t, p in zip(clips, truth, predicted, strict=True)]
    )  # (K, L, h, w, 3)
    n_clips, length, height, width, _ = rows.shape
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    png = folder / f"{name}.png"
    iio.imwrite(png, rows.transpose(0, 2, 1, 3, 4).reshape(n_clips * height, length * width, 3))
    return png, save_keyframe_gif(folder / f"{name}.gif", rows, per_column)
