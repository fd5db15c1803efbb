"""Where predicted pushing frames draw the puck and the pusher: the object half of the stage-1 gate.

A frame model can draw the wall exactly and the moving objects as a blur or not at all
(docs/pushing_models.md); its image loss hardly tells. These scores read each object by its flat
colour (:func:`keyin.envs.segmentation.puck_weights`; the scene is lit by ambient light only) from
the predicted frames and from the true frames, over the frames whose truth shows the object:

* **drawn**: the share of them where the prediction shows it too (colour mass above
  :data:`keyin.envs.segmentation.MIN_MASS`);
* **centroid error**: the pixel distance between the two colour centroids, over the frames drawn;
  **within 2 px**: the share of all frames (undrawn ones count as misses) drawn that close;
* **IoU**: intersection over union of the object's pixels (colour weight ≥ 1/2) in prediction and truth.

The true frames come from the analytic renderer, which gives each object exactly its geom colour, so
a true frame's colour mask is the renderer's mask and its centroid is the object's projected
position to within half a pixel (tests/envs/test_segmentation.py).
"""

from __future__ import annotations

from dataclasses import dataclass

import torch
from torch import Tensor

from keyin.envs.segmentation import PUCK_RGB, PUSHER_RGB, puck_centroid, puck_weights

OBJECT_COLOURS = {"puck": PUCK_RGB, "pusher": PUSHER_RGB}
MASK_LEVEL = 0.5  # a pixel belongs to an object's mask where its colour weight reaches this
CLOSE_PX = 2.0


@dataclass(frozen=True)
class ObjectPlacement:
    """How well predicted frames place one object, over the frames whose truth shows it."""

    drawn: float
    centroid_error_px: float  # mean over the frames drawn (NaN if none)
    median_error_px: float
    within_2px: float
    iou: float
    frames: int  # frames whose truth shows the object


@dataclass(frozen=True)
class FramePlacement:
    """Per-frame scores of one object, over the F frames whose truth shows it."""

    drawn: Tensor  # (F,) bool: the prediction shows it
    error_px: Tensor  # (F,) centroid distance; NaN where not drawn
    iou: Tensor  # (F,)

    @staticmethod
    def cat(parts: list["FramePlacement"]) -> "FramePlacement":
        """The frames of several batches as one."""
        return FramePlacement(*(torch.cat([getattr(part, name) for part in parts]) for name in ("drawn", "error_px", "iou")))

    def summary(self) -> ObjectPlacement:
        """Means and shares over the frames."""
        frames, nan = len(self.drawn), float("nan")
        errors = self.error_px[self.drawn]
        return ObjectPlacement(
            drawn=float(self.drawn.float().mean()) if frames else nan,
            centroid_error_px=float(errors.mean()) if len(errors) else nan,
            median_error_px=float(errors.median()) if len(errors) else nan,
            within_2px=float((errors <= CLOSE_PX).sum()) / frames if frames else nan,
            iou=float(self.iou.mean()) if frames else nan,
            frames=frames,
        )


def frame_placement(predicted: Tensor, truth: Tensor, colour: tuple[float, float, float]) -> FramePlacement:
    """One object's placement in each predicted frame whose true frame shows it.

    Args:
        predicted: (F, H, W, 3) predicted frames in [0, 1], channels last.
        truth: (F, H, W, 3) the true frames in [0, 1] or uint8.
        colour: the object's flat RGB colour.
    Returns:
        the scores of the frames whose truth shows the object.
    """
    if predicted.shape != truth.shape or predicted.ndim != 4 or predicted.shape[-1] != 3:
        raise ValueError(f"predicted and truth must both be (F, H, W, 3), got {tuple(predicted.shape)} and {tuple(truth.shape)}")
    true_centroids, _ = puck_centroid(truth, colour)  # (F, 2), NaN where the truth shows no object
    shown = ~true_centroids.isnan().any(-1)  # (F,)
    predicted, truth = predicted[shown], truth[shown]
    centroids, _ = puck_centroid(predicted, colour)  # (S, 2), NaN where not drawn
    predicted_mask = puck_weights(predicted, colour) >= MASK_LEVEL  # (S, H, W)
    true_mask = puck_weights(truth, colour) >= MASK_LEVEL
    union = (predicted_mask | true_mask).sum((-2, -1)).float()
    return FramePlacement(
        drawn=(~centroids.isnan().any(-1)).cpu(),
        error_px=(centroids - true_centroids[shown]).norm(dim=-1).cpu(),
        iou=((predicted_mask & true_mask).sum((-2, -1)).float() / union.clamp(min=1)).cpu(),
    )


def object_placement(predicted: Tensor, truth: Tensor, colour: tuple[float, float, float]) -> ObjectPlacement:
    """:func:`frame_placement` summed up over the frames (shapes as there)."""
    return frame_placement(predicted, truth, colour).summary()


def frame_placements(predicted: Tensor, truth: Tensor) -> dict[str, FramePlacement]:
    """:func:`frame_placement` of the puck and the pusher in (F, 3, H, W) frames in [0, 1] (the models' layout)."""
    predicted_last, truth_last = predicted.permute(0, 2, 3, 1), truth.permute(0, 2, 3, 1)
    return {name: frame_placement(predicted_last, truth_last, colour) for name, colour in OBJECT_COLOURS.items()}


def placement_scores(predicted: Tensor, truth: Tensor) -> dict[str, ObjectPlacement]:
    """:func:`object_placement` of the puck and the pusher.

    Args:
        predicted, truth: (F, 3, H, W) frames in [0, 1] (the models' layout).
    Returns:
        one :class:`ObjectPlacement` per object, by name.
    """
    return {name: frames.summary() for name, frames in frame_placements(predicted, truth).items()}
