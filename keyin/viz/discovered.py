"""Pictures of one video's discovered keyframes (keyin-discover): a contact sheet of the keyframes,
a timeline of the segments between them, and the video annotated frame by frame.

Colours as :mod:`keyin.viz.keyframes`: red a found keyframe, green a label, yellow both, grey the
conditioning frames that no window can mark.
"""

from __future__ import annotations

import functools
import math
from pathlib import Path
from typing import Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import torch  # noqa: E402
from PIL import Image, ImageDraw, ImageFont  # noqa: E402

from keyin.viz.figures import save_figure  # noqa: E402
from keyin.viz.keyframes import CONDITION, PREDICTED, TRUE, marked_frames, save_keyframe_gif  # noqa: E402

SHEET_COLUMNS = 6
SHEET_FONT = functools.lru_cache(ImageFont.load_default)  # size in pixels -> Pillow's own font
SHEET_FRAME_PIXELS = 150  # about how wide a keyframe is drawn on the contact sheet
CAPTION_PIXELS, TITLE_PIXELS, SHEET_GAP = 40, 30, 20  # the sheet's caption band per row, title band, and gaps
STRIP_HEIGHT = 6  # pixels of the position bar under each annotated frame (before enlarging)


def rgb(colour: tuple[int, int, int]) -> tuple[float, ...]:
    return tuple(value / 255 for value in colour)


def save_contact_sheet(path: Path, images: np.ndarray, captions: Sequence[str], title: str) -> Path:
    """The keyframes in a grid, each with its caption above it, in reading order.

    Drawn with Pillow onto one picture (every frame enlarged by whole pixels, about 150 wide): a
    matplotlib figure of one axes per keyframe took seconds for a long video's hundred keyframes.

    Args:
        images: (K, H, W, C) uint8 frames, C = 1 or 3; K may be 0.
        captions: one per image.
    """
    if len(images) != len(captions):
        raise ValueError(f"save_contact_sheet needs one caption per image, got {len(captions)} for {len(images)}")
    columns = max(1, min(SHEET_COLUMNS, len(images)))
    rows = max(1, math.ceil(len(images) / columns))
    height, width = images.shape[1:3] if len(images) else (SHEET_FRAME_PIXELS, SHEET_FRAME_PIXELS)
    scale = max(1, round(SHEET_FRAME_PIXELS / width))
    cell_height, cell_width = CAPTION_PIXELS + height * scale + SHEET_GAP, width * scale + SHEET_GAP
    sheet_width = max(columns * cell_width, int(SHEET_FONT(13).getlength(title)) + SHEET_GAP)  # room for the title
    sheet = np.full((TITLE_PIXELS + rows * cell_height, sheet_width, 3), 255, dtype=np.uint8)
    for index, image in enumerate(images):
        row, column = divmod(index, columns)
        top, left = TITLE_PIXELS + row * cell_height + CAPTION_PIXELS, column * cell_width + SHEET_GAP // 2
        sheet[top : top + height * scale, left : left + width * scale] = image.repeat(scale, 0).repeat(scale, 1)
    picture = Image.fromarray(sheet)
    draw = ImageDraw.Draw(picture)
    draw.text((sheet.shape[1] / 2, TITLE_PIXELS / 2), title, fill="black", font=SHEET_FONT(13), anchor="mm")
    for index, caption in enumerate(captions):
        row, column = divmod(index, columns)
        bottom = TITLE_PIXELS + row * cell_height + CAPTION_PIXELS - 4
        draw.multiline_text((column * cell_width + cell_width / 2, bottom), caption, fill="black", font=SHEET_FONT(11),
                            anchor="md", align="center")
    if not len(images):
        draw.text((sheet.shape[1] / 2, TITLE_PIXELS + cell_height / 2), "no keyframes found", fill="black",
                  font=SHEET_FONT(13), anchor="mm")
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    picture.save(path)
    return path


def save_timeline(
    path: Path,
    n_frames: int,
    keyframes: Sequence[int],
    scores: Sequence[float],
    first_candidate: int,
    fps: float | None,
    labels: Sequence[int] | None,
    title: str,
) -> Path:
    """The video's segments as a bar over its frames, the keyframes' scores as stems above it and, when
    there are labels, the labelled segments as a second bar beside it.

    Args:
        n_frames: the original video's frames; keyframes, labels and ``first_candidate`` (the first
            frame a keyframe may be, before it the conditioning frames) count them from 0.
        scores: one per keyframe, in [0, 1].
        fps: the video's frame rate, for a seconds axis; None without one.
    """
    rows = {"found": (keyframes, PREDICTED)} | ({"labels": (labels, TRUE)} if labels is not None else {})
    fig, (stems, bars) = plt.subplots(
        2, 1, sharex=True, figsize=(8, 1.4 + 0.35 * len(rows)), gridspec_kw={"height_ratios": [1.4, 0.5 * len(rows)]}
    )
    stems.vlines(keyframes, 0, scores, colors=[rgb(PREDICTED)])
    stems.plot(keyframes, scores, "o", color=rgb(PREDICTED), markersize=3)
    stems.set_ylim(0, 1.05)
    stems.set_ylabel("score", fontsize=7)
    stems.set_title(title, fontsize=8)
    for y, (name, (marks, colour)) in enumerate(reversed(rows.items())):
        edges = [0, *sorted(marks), n_frames]
        spans = [(left, right - left) for left, right in zip(edges[:-1], edges[1:]) if right > left]
        shades = [rgb(colour) + ((0.35 if i % 2 else 0.65),) for i in range(len(spans))]
        bars.broken_barh(spans, (y + 0.1, 0.8), facecolors=shades)
        bars.vlines(list(marks), y + 0.05, y + 0.95, colors=[rgb(colour)], linewidth=1.5)
    bars.broken_barh([(0, first_candidate)], (0, len(rows)), facecolors=[rgb(CONDITION) + (0.6,)])
    bars.set_yticks([y + 0.5 for y in range(len(rows))], list(reversed(rows)), fontsize=7)
    bars.set_xlim(0, n_frames)
    bars.set_xlabel("frame of the original video", fontsize=7)
    if fps:
        seconds = stems.secondary_xaxis("top", functions=(lambda f: f / fps, lambda s: s * fps))
        seconds.set_xlabel("seconds", fontsize=7)
        seconds.tick_params(labelsize=6)
    for ax in (stems, bars):
        ax.tick_params(labelsize=6)
    fig.tight_layout()
    return save_figure(fig, path, dpi=110)


def position_strips(width: int, n_frames: int, found: Sequence[int], labels: Sequence[int]) -> np.ndarray:
    """(T, STRIP_HEIGHT, width, 3) uint8, one bar per frame: where that frame is in the video (white),
    the part played so far lighter, labels ticked green above and keyframes red below. The ticks are
    drawn once and each frame only chooses its columns, so a long video costs O(T · width)."""
    def column(frames: np.ndarray) -> np.ndarray:
        return np.minimum(width - 1, frames * width // max(n_frames, 1))

    ahead, played = (np.full((STRIP_HEIGHT, width, 3), shade, dtype=np.uint8) for shade in (40, 90))
    half = STRIP_HEIGHT // 2
    for marks, colour, rows in ((labels, TRUE, slice(None, half)), (found, PREDICTED, slice(half, None))):
        ticks = column(np.asarray(list(marks), dtype=np.int64))
        for strip in (ahead, played):
            strip[rows, ticks] = colour
    now = column(np.arange(n_frames))  # (T,)
    strips = np.where((np.arange(width) < now[:, None])[:, None, :, None], played, ahead)  # (T, h, w, 3)
    strips[np.arange(n_frames), :, now] = 255
    return strips


def save_annotated_gif(
    path: Path, frames: np.ndarray, n_cond: int, found: Sequence[int], labels: Sequence[int] | None, duration_ms: float
) -> Path:
    """The video as the model saw it, every frame bordered (keyframes red, labels green, both yellow,
    the first ``n_cond`` grey) over a bar of where it is in the video.

    Args:
        frames: (T, H, W, C) uint8 kept frames, C = 1 or 3.
        found, labels: kept-frame indices.
        duration_ms: how long each frame shows.
    """
    clip = torch.from_numpy(np.ascontiguousarray(frames)).permute(0, 3, 1, 2).float().div_(255.0)
    labels = labels or []
    future = lambda marks: [k - n_cond for k in marks]  # noqa: E731  (marked_frames counts after the conditioning frames)
    marked = marked_frames(clip, n_cond, future(labels), future(found))  # (T, h, w, 3)
    strips = position_strips(marked.shape[2], len(frames), found, labels)
    return save_keyframe_gif(path, np.concatenate([marked, strips], axis=1)[None], duration_ms=duration_ms, side=128)
