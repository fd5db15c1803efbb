"""KEYIN's high-level planner: CEM over the keyframe latents (paper Alg. 1 and 4, App. 10).

The candidates are z ∈ R^{L×Zk} (L = M, the model's keyframes; Zk its keyframe latent size), drawn
from N(μ, σ²) starting at the prior N(0, I) and refit to the elites by the generic
:func:`keyin.planning.cem.cem`. A candidate is rolled out in prior mode from the start image
(LSTM_cond on its embedding, LSTM_key fed the given z^t; paper Alg. 1) and only its last keyframe is
decoded for the cost: the pixel distance between the puck centre in K̂^L and in the goal image,
by the colour segmentation the servo applies to subgoal images; a K̂^L without a puck costs the
image diagonal and is counted. Nothing but z is random (eval mode; the interpolator is not used:
subgoals are keyframes), so the best candidate of all iterations is decoded once more for the
subgoals K̂^1..K̂^L. Jumpy plans the same way with its fixed-offset model (``planner=jumpy``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
import torch

from keyin.lit.keyframes import KeyframeModule
from keyin.models import KEYIN
from keyin.planning.cem import CEMParams, cem
from keyin.planning.servo import subgoal_pixels
from keyin.planning.subgoals import Subgoals
from keyin.planning.tasks import PlanningTask
from keyin.planning.trained import TrainedPlanner, conditioning_frames, tensor_to_images

# (n, L, Zk) latents and ``last_only`` -> (n, K, H, W, 3) uint8 keyframes: K = L, or 1 (K̂^L) if last_only.
KeyframeRenderer = Callable[[np.ndarray, bool], np.ndarray]


@dataclass(frozen=True)
class LatentPlan:
    """Outcome of :func:`plan_keyframes`.

    Attributes:
        z: (L, Zk) the lowest-cost latents of all iterations.
        keyframes: (L, H, W, 3) uint8, their keyframes K̂^1..K̂^L.
        cost: pixel distance between the puck in K̂^L and in the goal (the diagonal if K̂^L shows none).
        samples_without_puck: candidates, over all iterations, whose K̂^L showed no puck.
    """

    z: np.ndarray
    keyframes: np.ndarray
    cost: float
    samples_without_puck: int


def plan_keyframes(
    render: KeyframeRenderer,
    goal: np.ndarray,
    latent_shape: tuple[int, int],
    params: CEMParams,
    rng: np.random.Generator,
) -> LatentPlan:
    """CEM over (L, Zk) latents from N(0, I) for the keyframes whose last one puts the puck where
    the goal image (H, W, 3) shows it."""
    goal_pixel = subgoal_pixels(goal[None])[0]  # (2,)
    if np.isnan(goal_pixel).any():
        raise ValueError("the goal image shows no puck")
    diagonal = float(np.hypot(*goal.shape[:2]))
    without_puck = []

    def cost(z: np.ndarray) -> np.ndarray:
        distances = np.linalg.norm(subgoal_pixels(render(z, True)[:, -1]) - goal_pixel, axis=-1)  # (n,), NaN: no puck
        missing = np.isnan(distances)
        without_puck.append(int(missing.sum()))
        return np.where(missing, diagonal, distances)

    result = cem(cost, np.zeros(latent_shape), np.ones(latent_shape), params, rng)
    return LatentPlan(result.best, render(result.best[None], False)[0], result.best_cost, sum(without_puck))


class PriorKeyframes:
    """A :data:`KeyframeRenderer`: a KEYIN model in prior mode from one start image, deterministic
    given z.

    Args:
        model: a trained :class:`keyin.models.KEYIN` (or Jumpy's) in eval mode.
        start: (H, W, 3) uint8, used as every conditioning frame (pushing has one).
    """

    def __init__(self, model: KEYIN, start: np.ndarray) -> None:
        self.model = model
        self.device = next(model.parameters()).device
        frames = conditioning_frames(start, model.encoder.image_shape, model.n_cond, self.device)
        with torch.no_grad():
            self.cond_emb = model.encoder(frames)  # (1, n_cond, E)

    @torch.no_grad()
    def __call__(self, z: np.ndarray, last_only: bool) -> np.ndarray:
        latents = torch.as_tensor(z, dtype=torch.float32, device=self.device)  # (n, L, Zk)
        images = self.model.keyframe_images(self.cond_emb.expand(len(latents), -1, -1), latents, last_only)
        return tensor_to_images(images)  # (n, K, H, W, C)


@dataclass(frozen=True)
class LatentCEMPlanner(TrainedPlanner):
    """A learned planner that runs :func:`plan_keyframes` over its model's latents; subclasses say
    how the model renders latents and what their shape is.

    Attributes:
        samples, elites, iterations: the latent CEM's budget (paper: 200, 10, 3).
    """

    samples: int = 200
    elites: int = 10
    iterations: int = 3

    def renderer(self, module: Any, start: np.ndarray) -> KeyframeRenderer:
        """The model's :data:`KeyframeRenderer` from the start image (H, W, 3)."""
        raise NotImplementedError

    def latent_shape(self, module: Any) -> tuple[int, int]:
        """The shape of one candidate."""
        raise NotImplementedError

    def __call__(
        self, start: np.ndarray, goal: np.ndarray, task: PlanningTask, rng: np.random.Generator
    ) -> Subgoals:
        module = self.module()
        params = CEMParams(self.samples, self.elites, self.iterations)
        plan = plan_keyframes(self.renderer(module, start), goal, self.latent_shape(module), params, rng)
        return Subgoals(
            plan.keyframes, {"plan_cost_px": plan.cost, "plan_samples_without_puck": plan.samples_without_puck}
        )


@dataclass(frozen=True)
class LatentCEMSubgoals(LatentCEMPlanner):
    """``planner=keyin`` and ``planner=jumpy``: the keyframes of the best latents are the subgoals."""

    stage: ClassVar[str] = "keyframes"

    def renderer(self, module: KeyframeModule, start: np.ndarray) -> KeyframeRenderer:
        return PriorKeyframes(module.model, start)

    def latent_shape(self, module: KeyframeModule) -> tuple[int, int]:
        return module.model.predictor.n_keyframes, module.model.predictor.latent_dim
