"""A trained stage 2 (KEYIN, Jumpy, Static) read by a decoding rule at its prices, without Lightning.

:class:`KeyframeReader` pairs a :class:`keyin.models.KEYIN` with the rule of
:data:`keyin.decode.registry.RULES` its checkpoint names and that rule's :class:`Prices`: keyin-eval,
keyin-discover, keyin-figures and keyin-plan build it from a checkpoint with torch alone
(:meth:`KeyframeReader.from_hparams`), and the LightningModule that trains the model
(:class:`keyin.lit.keyframes.KeyframeModule`) reads its own model through one when it validates, so
both find the same keyframes.
"""

from __future__ import annotations

import functools
from typing import Any, Callable, Mapping, Sequence

import torch
from torch import nn

from keyin.decode.flat_hparams import upgrade_keyframe_hparams
from keyin.decode.prices import Prices
from keyin.decode.registry import RULES, model_rule, rule_named
from keyin.decode.rules import keyin_keyframe_probabilities
from keyin.decode.segment_costs import video_interpolation_costs
from keyin.decode.segmentation import KeyframeCost
from keyin.losses.image import frame_pixel_weights, future_pixel_weights
from keyin.models import KEYIN
from keyin.models.config import KEYINConfig
from keyin.models.modes import evaluating


def prices_of(hparams: Mapping[str, Any]) -> Prices:
    """The prices a stage 2's hyper-parameters set: ``map_keyframe_cost``, ``map_boundary_weight``
    and ``map_candidate_logit``."""
    return Prices(hparams["map_keyframe_cost"], hparams["map_boundary_weight"], hparams["map_candidate_logit"])


class KeyframeReader(nn.Module):
    """A stage-2 model read by a decoding rule: its keyframes, segment costs and keyframe probabilities.

    The model is a submodule, so the reader's state dict names are
    :class:`keyin.lit.keyframes.KeyframeModule`'s (``model.*``) and ``.to`` / ``.eval`` reach it.

    Args:
        model: the trained KEYIN (or Jumpy / Static) model.
        config: the model's sizes and choices.
        discovery: the rule of :data:`keyin.decode.registry.RULES` it discovers by unless told another.
        prices: that rule's prices (:class:`keyin.decode.prices.Prices`).
    """

    stage = "keyframes"

    def __init__(self, model: KEYIN, config: KEYINConfig, discovery: str, prices: Prices) -> None:
        super().__init__()
        model_rule(discovery, config.predictor.offset_evidence)
        self.model, self.config, self.discovery, self.saved_prices = model, config, discovery, prices
        self.training = model.training  # a reader over a model in eval mode says so

    @classmethod
    def from_hparams(cls, **hparams: Any) -> "KeyframeReader":
        """The reader of a fresh model built from a checkpoint's ``hyper_parameters`` (``keyin_stage``
        "keyframes"; those saved before the typed configs upgraded:
        :func:`keyin.decode.flat_hparams.upgrade_keyframe_hparams`); the checkpoint's state dict
        then fills its weights."""
        hparams = upgrade_keyframe_hparams(hparams)
        config = KEYINConfig.from_dict(hparams["net"])
        return cls(KEYIN.from_config(config), config, hparams["discovery"], prices_of(hparams))

    @property
    def device(self) -> torch.device:
        return next(self.model.parameters()).device

    def pixel_weights(self, clips: torch.Tensor) -> torch.Tensor | None:
        """(B, L, C, H, W) weights of the image likelihood stage 1 was trained with, or None."""
        return frame_pixel_weights(clips, self.config.frames)

    def prices(self, keyframe_cost: KeyframeCost | None = None, candidate_logit: float | None = None) -> Prices:
        """The saved prices, the price per keyframe and the candidates' least logit replaced where given."""
        saved = self.saved_prices
        return Prices(saved.keyframe_cost if keyframe_cost is None else keyframe_cost, saved.boundary_weight,
                      saved.candidate_logit if candidate_logit is None else candidate_logit)

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
        :data:`keyin.decode.registry.RULES` (default: :attr:`discovery`) at :meth:`prices`; a rule that
        reads segment costs takes the segments' (B, N, S) BCE from ``costs`` where given."""
        clips = clips.to(self.device)
        with evaluating(self.model):
            return rule_named(discovery or self.discovery)(
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
        with evaluating(self.model):
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
            (T - 1, S) on the model's device, or None.
        """
        if not self.config.frames.plain_bce:
            return None
        pixels = frames.permute(0, 3, 1, 2).flatten(1)  # (T, C·H·W) uint8, as the clips' layout; moved a block at a time
        embeddings = []
        with evaluating(self.model):
            for first in range(0, len(frames), block):
                chunk = pixels[first : first + block].to(self.device).float().div_(255.0)
                embeddings.append(self.model.encoder(chunk.view(1, -1, *self.model.encoder.image_shape))[0])
            return video_interpolation_costs(self.model.interpolator, self.model.decoder, torch.cat(embeddings), pixels,
                                             block, None if keep is None else keep.to(self.device))

    @torch.no_grad()
    def keyframe_probabilities(self, clips: torch.Tensor, future_length: torch.Tensor) -> torch.Tensor:
        """(B, N) probability of a keyframe at each future frame of (B, L, C, H, W) clips
        (:func:`keyin.decode.rules.keyin_keyframe_probabilities`), on the CPU."""
        with evaluating(self.model):
            return keyin_keyframe_probabilities(self.model, clips.to(self.device), future_length.to(self.device)).cpu()

    def discoverers(self, name: str, rules: Sequence[str] | None = None) -> dict[str, Callable]:
        """The discovery rules to score, by method name: :attr:`discovery` (named ``name``) first;
        with offset evidence also the other variants of :data:`keyin.decode.registry.RULES`, as
        ``<name>_<rule>``. ``rules`` picks among those and the other rules the model has what they
        read for (with offset evidence ``map_pruned``; any model: stage 1's ``segmentation`` at the same price)."""
        own, evidence = rule_named(self.discovery), self.config.predictor.offset_evidence
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
