"""What a decoding rule may read besides the model, without torch: the label-free keyframe price
:data:`KNEE`, the candidates' least boundary logit and :class:`Prices` (:mod:`keyin.decode.registry`'s rules take them)."""

from __future__ import annotations

from dataclasses import dataclass

KNEE = "knee"  # the label-free keyframe price: each clip's count at the knee of its cost curve
MAP_CANDIDATE_LOGIT = -4.0  # map_pruned: the boundary logit a frame needs to be a candidate keyframe (docs/decisions.md)


@dataclass(frozen=True)
class Prices:
    """The numbers a rule may read besides the model: ``keyframe_cost`` nats per keyframe (or
    :data:`KNEE`), ``boundary_weight`` times the boundary scores as a prior, and
    ``candidate_logit``, the least boundary logit of a candidate keyframe of a pruning rule."""

    keyframe_cost: float | str = 0.0
    boundary_weight: float = 0.0
    candidate_logit: float = MAP_CANDIDATE_LOGIT
