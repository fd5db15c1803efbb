"""A trained stage 2 (KEYIN, Jumpy, Static) and its discovery rules, without Lightning.

:class:`KeyframeRules` holds what finding keyframes asks of a stage-2 model; the LightningModule
that trains it (:class:`keyin.lit.keyframes.KeyframeModule`) and :class:`TrainedKeyframes`, which
keyin-eval, keyin-discover, keyin-figures and keyin-plan build from a checkpoint with torch alone,
share it, so both find the same keyframes.
"""

from __future__ import annotations

import functools
from typing import Any, Callable, Sequence

import torch
from torch import nn

from keyin.decode.prices import Prices
from keyin.decode.registry import RULES, model_rule, rule_named
from keyin.decode.rules import keyin_keyframe_probabilities
from keyin.decode.segment_costs import video_interpolation_costs
from keyin.decode.segmentation import KeyframeCost
from keyin.models.modes import evaluating
from keyin.decode.flat_hparams import upgrade_keyframe_hparams
from keyin.losses.image import changed_pixel_weights, future_pixel_weights
from keyin.models import KEYIN
from keyin.models.config import KEYINConfig

class Hyperparameters(dict):
    """A dict whose keys read and write as attributes too (``hparams.discovery``), as Lightning's."""

    def __getattr__(self, key: str) -> Any:
        try:
            return self[key]
        except KeyError:
            raise AttributeError(key) from None

    def __setattr__(self, key: str, value: Any) -> None:
        self[key] = value


class KeyframeRules:
    """The discovery rules of a stage-2 model; the class that mixes it in has ``model`` (a
    :class:`keyin.models.KEYIN`), its ``config``, ``hparams`` (the discovery rule's) and ``device``."""

    model: KEYIN
    config: KEYINConfig
    hparams: Any
    device: torch.device

    def pixel_weights(self, clips: torch.Tensor) -> torch.Tensor | None:
        """(B, L, C, H, W) weights of the image likelihood stage 1 was trained with, or None."""
        frames = self.config.frames
        return changed_pixel_weights(clips, frames.foreground_weight, frames.foreground_threshold)

    def prices(self, keyframe_cost: KeyframeCost | None = None, candidate_logit: float | None = None) -> Prices:
        """The module's ``map_keyframe_cost``, ``map_boundary_weight`` and ``map_candidate_logit``, the
        price and the candidates' least logit replaced where given."""
        hp = self.hparams
        return Prices(hp.map_keyframe_cost if keyframe_cost is None else keyframe_cost, hp.map_boundary_weight,
                      hp.map_candidate_logit if candidate_logit is None else candidate_logit)

    @torch.no_grad()
    def discover(
        self,
        clips: torch.Tensor,
        future_length: torch.Tensor,
        discovery: str | None = None,
        keyframe_cost: KeyframeCost | None = None,
        costs: torch.Tensor | None = None,
        candidate_logit: float | None = None,
    ) -> list[list[int]]:
        """Keyframe positions inside each of (B, L, C, H, W) clips by a rule of
        :data:`keyin.decode.registry.RULES` (default: the module's ``discovery``) at :meth:`prices`;
        a rule that reads segment costs takes the segments' (B, N, S) BCE from ``costs`` where given."""
        clips = clips.to(self.device)
        with evaluating(self):
            return rule_named(discovery or self.hparams.discovery)(
                self.model, clips, future_length.to(self.device), self.prices(keyframe_cost, candidate_logit),
                future_pixel_weights(self.pixel_weights(clips), self.model.n_cond), costs,
            )

    @torch.no_grad()
    def kept_segments(
        self, clips: torch.Tensor, future_length: torch.Tensor, discovery: str, candidate_logit: float | None = None
    ) -> torch.Tensor | None:
        """(B, N, S) bool, the segments a rule prices in each of (B, L, C, H, W) clips, None for all
        (:meth:`keyin.decode.registry.Rule.kept_segments`)."""
        rule = rule_named(discovery)
        with evaluating(self):
            read = rule.read(self.model, clips.to(self.device), future_length.to(self.device))
            return rule.kept_segments(read, self.prices(candidate_logit=candidate_logit))

    @torch.no_grad()
    def video_costs(self, frames: torch.Tensor, keep: torch.Tensor | None = None, block: int = 256) -> torch.Tensor | None:
        """The interpolation BCE of every segment of a whole video, which all its windows share
        (:func:`keyin.decode.segment_costs.video_interpolation_costs`); None where the BCE weighs
        pixels by their change within a window (``foreground_weight``), so that windows differ.

        Args:
            frames: (T, H, W, C) uint8, the video's kept frames at the model's size.
            keep: (T - 1, S) bool, only these segments (the others ``inf``); None: all.
        Returns:
            (T - 1, S) on the module's device, or None.
        """
        if not self.config.frames.plain_bce:
            return None
        pixels = frames.permute(0, 3, 1, 2).flatten(1)  # (T, C·H·W) uint8, as the clips' layout; moved a block at a time
        embeddings = []
        with evaluating(self):
            for first in range(0, len(frames), block):
                chunk = pixels[first : first + block].to(self.device).float().div_(255.0)
                embeddings.append(self.model.encoder(chunk.view(1, -1, *self.model.encoder.image_shape))[0])
            return video_interpolation_costs(self.model.interpolator, self.model.decoder, torch.cat(embeddings), pixels,
                                             block, None if keep is None else keep.to(self.device))

    @torch.no_grad()
    def keyframe_probabilities(self, clips: torch.Tensor, future_length: torch.Tensor) -> torch.Tensor:
        """(B, N) probability of a keyframe at each future frame of (B, L, C, H, W) clips
        (:func:`keyin.decode.rules.keyin_keyframe_probabilities`), on the CPU."""
        with evaluating(self):
            return keyin_keyframe_probabilities(self.model, clips.to(self.device), future_length.to(self.device)).cpu()

    def discoverers(self, name: str, rules: Sequence[str] | None = None) -> dict[str, Callable]:
        """The discovery rules to score, by method name: the configured one (named ``name``) first;
        with offset evidence also the other variants of :data:`keyin.decode.registry.RULES`, as
        ``<name>_<rule>``. ``rules`` picks among those and the other rules the model has what they
        read for (with offset evidence ``map_pruned``; any model: stage 1's ``segmentation`` at the same price)."""
        own, evidence = rule_named(self.hparams.discovery), self.config.predictor.offset_evidence
        scored = [own] + [rule for rule in RULES.values() if evidence and rule.variant and rule is not own]
        if rules is not None:
            choosable = scored + [rule for rule in RULES.values()
                                  if not rule.variant and rule.runs_on(evidence) and rule not in scored]
            unknown = [asked for asked in rules if asked not in [rule.name for rule in choosable]]
            if unknown:
                raise ValueError(f"this model discovers by {[rule.name for rule in choosable]}, not {unknown}")
            scored = [rule for rule in choosable if rule.name in rules]
        return {
            name if rule is own else f"{name}_{rule.name}": functools.partial(self.discover, discovery=rule.name)
            for rule in scored
        }


class TrainedKeyframes(KeyframeRules, nn.Module):
    """A trained stage 2 built from its checkpoint's hyper-parameters (``keyin_stage`` "keyframes"),
    for inference only; its state dict's names are :class:`keyin.lit.keyframes.KeyframeModule`'s.

    Args:
        hparams: the checkpoint's ``hyper_parameters`` (those of a checkpoint saved before the typed
            configs upgraded: :func:`keyin.decode.flat_hparams.upgrade_keyframe_hparams`).
    """

    stage = "keyframes"

    def __init__(self, **hparams: Any) -> None:
        super().__init__()
        hparams = upgrade_keyframe_hparams(hparams)
        self.config = KEYINConfig.from_dict(hparams["net"])
        model_rule(hparams["discovery"], self.config.predictor.offset_evidence)
        object.__setattr__(self, "hparams", Hyperparameters(hparams))
        self.model = KEYIN.from_config(self.config)

    @property
    def device(self) -> torch.device:
        return next(self.parameters()).device
