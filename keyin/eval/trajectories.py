"""Puck trajectories of the pushing scene (the paper's Fig. 6): tracks read from frames by colour
segmentation, and which way round the wall they pass (:func:`keyin.envs.geometry.passing_side`)."""

from __future__ import annotations

from typing import Any

import numpy as np
from torch import Tensor
from torch.utils.data import DataLoader, Dataset

from keyin.envs.geometry import apply_homography, end_side, passing_side, side_fractions, top_view_homography
from keyin.envs.segmentation import puck_centroid


def puck_tracks(videos: Tensor) -> np.ndarray:
    """The puck's pixel (column, row) centroid in every frame (:func:`puck_centroid`).

    Args:
        videos: (B, L, 3, H, W) RGB frames in [0, 1].
    Returns:
        (B, L, 2) float; NaN where a frame shows no puck (e.g. a prediction's black frames past
        its last keyframe).
    """
    centroids, _ = puck_centroid(videos.permute(0, 1, 3, 4, 2))
    return centroids.cpu().numpy().astype(np.float64)


def to_world(pixels: np.ndarray, image_size: int) -> np.ndarray:
    """(..., 2) pixel (column, row) coordinates of the top camera -> world (x, y); NaN stays NaN."""
    return apply_homography(np.linalg.inv(top_view_homography(image_size)), pixels)


def track_sides(tracks: np.ndarray, walls: np.ndarray, image_size: int) -> list[str]:
    """Which way each pixel track passes its wall (:func:`passing_side`).

    Args:
        tracks: (B, T, 2) pixel coordinates, NaN where the puck is not seen.
        walls: (B, 5) the wall of each track's scene, or (5,) one for all.
    """
    walls = np.broadcast_to(walls, (len(tracks), 5))
    return [passing_side(track, wall) for track, wall in zip(to_world(tracks, image_size), walls)]


def demonstration_sides(clips: Dataset, walls: np.ndarray, sides: np.ndarray, batch_size: int) -> dict[str, Any]:
    """How the demonstrations of ``clips`` pass their walls, read from their frames as the samples'
    are (:func:`track_sides`), beside the detour side the demonstrator stored (``side``).

    Args:
        walls: (B, 5) and sides: (B,) +1 / -1, of every clip, in order.
    Returns:
        :func:`side_fractions` of the frames' sides, ``stored_side`` (those of the stored sides) and
        ``agreement`` (the fraction of clips where the two agree).
    """
    image_size = clips[0]["frames"].shape[-1]
    read = []
    for batch in DataLoader(clips, batch_size=batch_size, shuffle=False):
        scenes = walls[len(read) : len(read) + len(batch["frames"])]
        read += track_sides(puck_tracks(batch["frames"]), scenes, image_size)
    stored = [end_side(side, wall) for side, wall in zip(sides, walls)]
    agreement = float(np.mean([a == b for a, b in zip(read, stored)]))
    return {**side_fractions(read), "stored_side": side_fractions(stored), "agreement": agreement}
