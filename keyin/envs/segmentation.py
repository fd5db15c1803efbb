"""Puck centroid by colour segmentation: ground-truth check of the camera and the planner's cost.

Each pixel gets a soft weight ``w = clip(1 - d / tau, 0, 1)`` from the Euclidean distance ``d``
between its RGB colour (in [0, 1]) and the puck colour (paper App. 10); the centroid is the
weighted mean pixel centre, in the continuous (column, row) convention of
:mod:`keyin.envs.geometry` (pixel ``[r, c]`` has centre ``(c + 0.5, r + 0.5)``). Works on numpy
arrays and on torch tensors (predicted images), channels last, any leading batch shape.
"""

from __future__ import annotations

from typing import Any

import numpy as np

# The rendered puck colour under the scene's flat, ambient-only lighting (keyin.envs.pushing).
PUCK_RGB = (0.55, 0.15, 0.75)
PUSHER_RGB = (0.95, 0.55, 0.1)
DEFAULT_TAU = 0.25
# Total weight below which a frame is said to show no puck.
MIN_MASS = 0.5


def _is_torch(array: Any) -> bool:
    return type(array).__module__.startswith("torch")


def puck_weights(images: Any, colour: tuple[float, float, float] = PUCK_RGB, tau: float = DEFAULT_TAU) -> Any:
    """Soft puck mask.

    Args:
        images: (..., H, W, 3) uint8 in [0, 255] or float in [0, 1] (numpy or torch).
    Returns:
        (..., H, W) float weights in [0, 1], same library as ``images``.
    """
    if _is_torch(images):
        import torch

        pixels = images.float() / 255.0 if images.dtype == torch.uint8 else images.float()
        target = torch.as_tensor(colour, dtype=pixels.dtype, device=pixels.device)
    else:
        images = np.asarray(images)
        pixels = images.astype(np.float32) / 255.0 if images.dtype == np.uint8 else images.astype(np.float32)
        target = np.asarray(colour, dtype=np.float32)
    distance = (((pixels - target) ** 2).sum(-1)) ** 0.5
    return (1.0 - distance / tau).clip(0.0, 1.0)


def puck_centroid(
    images: Any, colour: tuple[float, float, float] = PUCK_RGB, tau: float = DEFAULT_TAU
) -> tuple[Any, Any]:
    """Centroid of the puck-coloured pixels.

    Args:
        images: (..., H, W, 3) uint8 or float in [0, 1], numpy or torch.
    Returns:
        centroid: (..., 2) (column, row) pixel coordinates; NaN where the mass is below ``MIN_MASS``.
        mass: (...) total weight (about the puck's area in pixels; ~0 when it is not visible).
    """
    weights = puck_weights(images, colour, tau)
    height, width = weights.shape[-2:]
    if _is_torch(weights):
        import torch

        cols = torch.arange(width, dtype=weights.dtype, device=weights.device) + 0.5
        rows = torch.arange(height, dtype=weights.dtype, device=weights.device) + 0.5
        stack, nan = torch.stack, torch.tensor(float("nan"), dtype=weights.dtype, device=weights.device)
        where = torch.where
    else:
        cols = np.arange(width, dtype=np.float32) + 0.5
        rows = np.arange(height, dtype=np.float32) + 0.5
        stack, nan, where = np.stack, np.float32(np.nan), np.where
    mass = weights.sum((-2, -1))
    safe = where(mass > MIN_MASS, mass, mass * 0.0 + 1.0)
    u = (weights.sum(-2) * cols).sum(-1) / safe
    v = (weights.sum(-1) * rows).sum(-1) / safe
    centroid = stack([u, v], -1)
    return where((mass > MIN_MASS)[..., None], centroid, nan), mass


def centroid_distance(
    images: Any,
    targets: Any,
    colour: tuple[float, float, float] = PUCK_RGB,
    tau: float = DEFAULT_TAU,
) -> Any:
    """Pixel distance between the puck centroids of two image batches (the planner's image cost).

    A frame without a visible puck costs the image diagonal (docs/architecture.md, "Planning").

    Args:
        images, targets: (..., H, W, 3), broadcastable against each other.
    Returns:
        (...) distances in pixels.
    """
    first, _ = puck_centroid(images, colour, tau)
    second, _ = puck_centroid(targets, colour, tau)
    height, width = np.shape(images)[-3:-1] if not _is_torch(images) else images.shape[-3:-1]
    diagonal = float(np.hypot(height, width))
    distance = (((first - second) ** 2).sum(-1)) ** 0.5
    if _is_torch(distance):
        import torch

        return torch.nan_to_num(distance, nan=diagonal)
    return np.nan_to_num(distance, nan=diagonal)
