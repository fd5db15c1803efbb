"""TAP's high-level planner (paper §4.2): the subgoal TAP(start, goal); with
``depth`` d, recursively the subgoals between start and it and between it and the goal, 2^d − 1 in
time order. TAP is deterministic (eval mode), so the planner draws no randomness."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import ClassVar, TypeVar

import numpy as np
import torch

from keyin.planning.subgoals import Subgoals
from keyin.planning.tasks import PlanningTask
from keyin.planning.trained import TrainedPlanner, images_to_tensor, tensor_to_images

Image = TypeVar("Image")


def bisect_subgoals(between: Callable[[Image, Image], Image], start: Image, goal: Image, depth: int) -> list[Image]:
    """The 2^depth − 1 subgoals from ``start`` to ``goal`` in order: ``between(start, goal)``, with
    the subgoals of depth − 1 of each half before and after it."""
    if depth == 0:
        return []
    middle = between(start, goal)
    before = bisect_subgoals(between, start, middle, depth - 1)
    return [*before, middle, *bisect_subgoals(between, middle, goal, depth - 1)]


@dataclass(frozen=True)
class TAPSubgoals(TrainedPlanner):
    """``planner=tap``: subgoals predicted by a trained TAP (``keyin-train model=tap``).

    Attributes:
        depth: d >= 1, giving 2^d − 1 subgoals (paper: 1).
    """

    stage: ClassVar[str] = "tap"

    depth: int = 1

    def __post_init__(self) -> None:
        if isinstance(self.depth, bool) or not isinstance(self.depth, int) or self.depth < 1:
            raise ValueError(f"planner.tap_depth={self.depth!r} must be a positive integer")
        super().__post_init__()

    @torch.no_grad()
    def __call__(
        self, start: np.ndarray, goal: np.ndarray, task: PlanningTask, rng: np.random.Generator
    ) -> Subgoals:
        network = self.module().network  # in eval mode on the planner's device
        shape, device = network.encoder.image_shape, next(network.parameters()).device
        subgoals = bisect_subgoals(
            lambda first, last: torch.sigmoid(network(first[None], last[None]))[0],  # (C, H, W) in [0, 1]
            images_to_tensor(start, shape).to(device),
            images_to_tensor(goal, shape).to(device),
            self.depth,
        )
        return Subgoals(tensor_to_images(torch.stack(subgoals)), {})
