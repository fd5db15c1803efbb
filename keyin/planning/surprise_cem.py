"""The Surprise baseline's high-level planner (paper App. 9).

A CEM over SVG-FP's per-step latents z_{1:T} ∈ R^{T×Zs} (T = the model's N future frames) rolls the
frame predictor out from the start image, feeding each predicted embedding back as the next input,
and scores a rollout by the pixel distance between the puck in its last decoded frame and in the
goal image: the cost and the CEM are KEYIN's (:class:`keyin.planning.latent_cem.LatentCEMPlanner`).
The best rollout is then decoded whole, the inference network is run on the produced sequence
("to find the keyframes in a sequence sampled from the prior, we run the inference network on the
produced sequence"), and its M surprise keyframes (the KL peaks of
:func:`keyin.decode.surprise.surprise_keyframes`, with the model's shift) are the subgoals.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import torch

from keyin.decode.surprise import surprise_keyframes
from keyin.lit.surprise import SurpriseModule
from keyin.models import SVG
from keyin.planning.latent_cem import LatentCEMPlanner
from keyin.planning.trained import conditioning_frames, tensor_to_images


class SurpriseRollouts:
    """A :data:`keyin.planning.latent_cem.KeyframeRenderer` over SVG-FP prior rollouts: with
    ``last_only`` the last frame of each rollout, else its M surprise keyframes.

    Args:
        model: a trained :class:`keyin.models.SVG` in eval mode.
        start: (H, W, 3) uint8, used as every conditioning frame (pushing has one).
        n_keyframes: M, the subgoals per rollout.
        shift: added to a KL peak's future index (:func:`keyin.decode.surprise.surprise_keyframes`).
    """

    def __init__(self, model: SVG, start: np.ndarray, n_keyframes: int, shift: int) -> None:
        self.model, self.n_keyframes, self.shift = model, n_keyframes, shift
        self.device = next(model.parameters()).device
        self.cond_frames = conditioning_frames(start, model.encoder.image_shape, model.n_cond, self.device)
        with torch.no_grad():
            self.cond_emb, self.context = model.encode(self.cond_frames)  # (1, n_cond, E), skips of the start

    @torch.no_grad()
    def __call__(self, z: np.ndarray, last_only: bool) -> np.ndarray:
        embeddings = self.model.rollout(self.cond_emb, torch.as_tensor(z, dtype=torch.float32, device=self.device))  # (n, T, E)
        if last_only:
            return tensor_to_images(torch.sigmoid(self.model.decode(embeddings[:, -1:], self.context)))  # (n, 1, H, W, C)
        frames = torch.sigmoid(self.model.decode(embeddings, self.context))  # (n, T, C, H, W)
        clips = torch.cat([self.cond_frames.expand(len(frames), -1, -1, -1, -1), frames], 1)
        kl = self.model.surprise(clips).cpu()  # (n, n_cond + T): the inference network on the produced sequence
        lengths = torch.full((len(frames),), frames.shape[1])
        positions = surprise_keyframes(kl, lengths, self.model.n_cond, self.n_keyframes, self.shift)
        return np.stack([tensor_to_images(frames[row, picked]) for row, picked in enumerate(positions)])


@dataclass(frozen=True)
class SurpriseSubgoals(LatentCEMPlanner):
    """``planner=surprise``: the surprise keyframes of the best SVG-FP rollout are the subgoals."""

    stage: ClassVar[str] = "surprise"

    def renderer(self, module: SurpriseModule, start: np.ndarray) -> SurpriseRollouts:
        return SurpriseRollouts(module.model, start, module.hparams.n_keyframes, module.hparams.shift)

    def latent_shape(self, module: SurpriseModule) -> tuple[int, int]:
        return module.hparams.n_future, module.hparams.latent_dim
