"""The Surprise baseline's high-level planner (REFERENCE §4 "For planning", paper App. 9).

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
from keyin.planning.latent_cem import LatentCEMPlanner
from keyin.planning.trained import conditioning_frames, tensor_to_images


class SurpriseRollouts:
    """A :data:`keyin.planning.latent_cem.KeyframeRenderer` over SVG-FP prior rollouts: with
    ``last_only`` the last frame of each rollout, else its M surprise keyframes.

    Args:
        module: a trained :class:`SurpriseModule` in eval mode.
        start: (H, W, 3) uint8, used as every conditioning frame (pushing has one).
    """

    def __init__(self, module: SurpriseModule, start: np.ndarray) -> None:
        self.module = module
        self.cond_frames = conditioning_frames(start, module.encoder.image_shape, module.hparams.n_cond)
        with torch.no_grad():
            self.cond_emb, self.context = module.encode(self.cond_frames)  # (1, n_cond, E), skips of the start
            self.cond_z, _ = module.core.posterior_stats(self.cond_emb)  # (1, n_cond, Zs): posterior means

    @torch.no_grad()
    def rollout(self, z: torch.Tensor) -> torch.Tensor:
        """(n, T, E) predicted embeddings of the future frames, given (n, T, Zs) latents.

        As in training, step t reads the embedding of frame t - 1 and z_t. Conditioning frames are
        teacher-forced with their posterior means; after them every step reads its own prediction.
        """
        predictor, n = self.module.core.predictor, len(z)
        cond_emb, cond_z = self.cond_emb.expand(n, -1, -1), self.cond_z.expand(n, -1, -1)
        inputs = torch.cat([cond_emb[:, :-1], cond_z[:, 1:]], -1)  # (n, n_cond - 1, E + Zs)
        state = predictor(inputs)[1] if inputs.shape[1] else None
        previous, predicted = cond_emb[:, -1], []
        for step in range(z.shape[1]):
            output, state = predictor.step(torch.cat([previous, z[:, step]], -1), state)
            previous = torch.tanh(output)
            predicted.append(previous)
        return torch.stack(predicted, 1)

    @torch.no_grad()
    def __call__(self, z: np.ndarray, last_only: bool) -> np.ndarray:
        embeddings = self.rollout(torch.as_tensor(z, dtype=torch.float32))  # (n, T, E)
        if last_only:
            return tensor_to_images(torch.sigmoid(self.module.decode(embeddings[:, -1:], self.context)))  # (n, 1, H, W, C)
        frames = torch.sigmoid(self.module.decode(embeddings, self.context))  # (n, T, C, H, W)
        clips = torch.cat([self.cond_frames.expand(len(frames), -1, -1, -1, -1), frames], 1)
        kl = self.module.surprise(clips)  # (n, n_cond + T): the inference network on the produced sequence
        hp = self.module.hparams
        positions = surprise_keyframes(kl, torch.full((len(frames),), frames.shape[1]), hp.n_cond, hp.n_keyframes, hp.shift)
        return np.stack([tensor_to_images(frames[row, picked]) for row, picked in enumerate(positions)])


@dataclass(frozen=True)
class SurpriseSubgoals(LatentCEMPlanner):
    """``planner=surprise``: the surprise keyframes of the best SVG-FP rollout are the subgoals."""

    stage: ClassVar[str] = "surprise"

    def renderer(self, module: SurpriseModule, start: np.ndarray) -> SurpriseRollouts:
        return SurpriseRollouts(module, start)

    def latent_shape(self, module: SurpriseModule) -> tuple[int, int]:
        return module.hparams.n_future, module.hparams.latent_dim
