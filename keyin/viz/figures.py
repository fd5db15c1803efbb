"""The paper's figures from plain arrays: labelled rows of marked frames (Fig. 4, 5, 7, 10) and puck
trajectories over the pushing scene (Fig. 6)."""

from __future__ import annotations

from pathlib import Path
from typing import Mapping, Sequence

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

INCHES_PER_PIXEL = 0.0118  # a 36-pixel frame (32 + borders) is 0.42 in wide
LABEL_INCHES = 1.3  # the least room left of the strips for their labels
LABEL_POINTS, LABEL_PAD, LABEL_MARGIN = 7, 4, 6  # points: the labels' size, their gap to the strip and to the edge
STRIPS_DPI = 110  # labelled strips are measured and written at this resolution (text widths depend on it)
WALL_BLUE, START_PINK = "#2659d9", "#ff4fa0"


def save_figure(fig: plt.Figure, path: Path, dpi: int) -> Path:
    """Write ``fig`` to ``path`` (creating its folder) and close it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    return path


def label_inches(fig: plt.Figure, axes: Sequence[plt.Axes]) -> float:
    """The room left of the strips that the widest of the axes' y-labels needs as drawn at the figure's dpi (with its
    pad), at least ``LABEL_INCHES``: a long row name, such as a changed paper row's, is drawn whole."""
    renderer = fig.canvas.get_renderer()
    widest = max(ax.yaxis.label.get_window_extent(renderer).width for ax in axes) / fig.dpi
    return max(LABEL_INCHES, widest + (LABEL_PAD + LABEL_MARGIN) / 72)


def save_labeled_strips(strips: Sequence[np.ndarray], labels: Sequence[str], path: Path, title: str = "") -> Path:
    """One row per strip of frames, left to right, its label on the left.

    Args:
        strips: (N, h, w, 3) uint8 each, e.g. :func:`keyin.viz.keyframes.marked_frames` of a clip;
            all of one size.
        labels: one per strip ("\\n" for a second line).
    """
    if len(strips) != len(labels):
        raise ValueError(f"save_labeled_strips needs one label per strip, got {len(labels)} for {len(strips)}")
    n_frames, height, width, _ = strips[0].shape
    row, frames = height * INCHES_PER_PIXEL, n_frames * width * INCHES_PER_PIXEL  # inches
    fig_height = len(strips) * row * 1.25 + 0.3
    fig, axes = plt.subplots(len(strips), 1, squeeze=False, figsize=(frames + LABEL_INCHES, fig_height),
                             dpi=STRIPS_DPI)
    for ax, strip, label in zip(axes[:, 0], strips, labels):
        ax.imshow(np.concatenate(list(strip), axis=1), interpolation="nearest")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_ylabel(label, rotation=0, ha="right", va="center", fontsize=LABEL_POINTS, labelpad=LABEL_PAD)
    room = label_inches(fig, axes[:, 0])
    fig_width = frames + room
    fig.set_size_inches(fig_width, fig_height)
    if title:
        fig.suptitle(title, fontsize=8)
    top = 1 - (0.3 if title else 0.05) / fig_height
    fig.subplots_adjust(left=room / fig_width, right=0.995, top=top, bottom=0.05 / fig_height, hspace=0.2)
    return save_figure(fig, path, dpi=STRIPS_DPI)


def save_trajectories(
    background: np.ndarray,
    wall: np.ndarray,
    start: np.ndarray,
    panels: Mapping[str, Sequence[np.ndarray]],
    path: Path,
) -> Path:
    """Puck tracks over the scene, one panel per set (the paper's Fig. 6): the scene faded, the wall
    in blue, the start in pink, each track a black line.

    Args:
        background: (H, W, 3) uint8 image of the scene (a start frame).
        wall: (4, 2) the wall's corners, pixel (column, row) coordinates.
        start: (2,) the puck's start, pixel coordinates.
        panels: title -> tracks, each (T, 2) pixel coordinates in order; rows with a NaN (the puck not
            seen) are skipped, the points around them joined.
    """
    height, width = background.shape[:2]
    fig, axes = plt.subplots(1, len(panels), figsize=(3.4 * len(panels), 3.7), squeeze=False)
    for ax, (title, tracks) in zip(axes[0], panels.items()):
        ax.imshow(background, extent=(0, width, height, 0), alpha=0.35)
        ax.add_patch(plt.Polygon(wall, closed=True, color=WALL_BLUE, alpha=0.9))
        for track in tracks:
            seen = track[~np.isnan(track).any(axis=-1)]
            ax.plot(seen[:, 0], seen[:, 1], color="black", linewidth=0.6, alpha=0.35)
        ax.scatter([start[0]], [start[1]], s=40, color=START_PINK, zorder=3, edgecolors="white", linewidths=0.5)
        ax.set_xlim(0, width)
        ax.set_ylim(height, 0)
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(title, fontsize=8)
    fig.tight_layout()
    return save_figure(fig, path, dpi=120)
