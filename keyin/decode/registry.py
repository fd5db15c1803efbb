"""KEYIN's discovery rules as objects, one class each, and their registry :data:`RULES`.

A rule says what it reads of a stage-2 model (its boundary scores, the segments' interpolation BCE,
a pruning of the segments), how dear it is, and finds each clip's keyframes. The commands ask it
instead of testing its name, so a new rule is one class here (listed in :data:`RULES`) and one test
(docs/architecture.md, "Adding a decoding rule"). This module imports no torch: keyin-discover and
keyin-eval check ``rule=`` before they load a model (``--help`` answers at once); the math each
rule calls (:mod:`keyin.decode.rules` and below) is imported when it runs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, ClassVar

from keyin.decode.prices import Prices

if TYPE_CHECKING:
    from torch import Tensor

    from keyin.decode.rules import PosteriorRead
    from keyin.models.keyin import KEYIN

FAST_RULE_TOLERANCE = 0.01  # how far below the exact rule's validation F1 a cheaper rule may be and still be chosen


class Rule:
    """A way to read keyframes out of a trained :class:`keyin.models.KEYIN`, in posterior mode with
    the posterior mean and the offset evidence read along the argmax chain (what the readout reads).

    Subclasses set what they declare and :meth:`decode`; calling a rule validates its inputs, reads
    the model once and adds the sequence ends where it says so.
    """

    name: ClassVar[str]
    cost_rank: ClassVar[int]  # cheapest first: what rule=auto tries before the exact rule
    needs_boundary_scores: ClassVar[bool] = False  # reads stage 2's boundary scores (a model with offset_evidence)
    reads_segment_costs: ClassVar[bool] = False  # prices segments by interpolation BCE and keyframes at keyframe_cost
    prunes_segments: ClassVar[bool] = False  # prices only :meth:`kept_segments`, chosen by candidate_logit
    adds_sequence_ends: ClassVar[bool] = True  # closes a sequence that ends inside the window with a keyframe
    variant: ClassVar[bool] = False  # scored beside a model's own rule when the model has offset evidence

    def __call__(
        self,
        model: KEYIN,
        clips: Tensor,
        future_length: Tensor,
        prices: Prices = Prices(),
        pixel_weights: Tensor | None = None,
        costs: Tensor | None = None,
    ) -> list[list[int]]:
        """Per clip, the keyframe positions inside its valid frames.

        Args:
            model: a trained :class:`keyin.models.KEYIN` in eval mode.
            clips: (B, L, C, H, W) in [0, 1]; future_length: (B,) valid future frames.
            pixel_weights: (B, N, D) weights of the future pixels in the segments' BCE, None for plain BCE.
            costs: (B, N, S) that BCE of every segment if already known (a pruning rule: of at least
                its kept segments; :func:`keyin.decode.rules.map_keyframes`).
        """
        import torch

        from keyin.decode.rules import with_sequence_ends

        if costs is not None and not self.reads_segment_costs:
            raise ValueError(f"rule {self.name!r} reads no segment costs; pass costs only with "
                             f"{[rule.name for rule in RULES.values() if rule.reads_segment_costs]}")
        with torch.no_grad():
            positions = self.decode(self.read(model, clips, future_length), prices, pixel_weights, costs)
        if not self.adds_sequence_ends:
            return positions
        return with_sequence_ends(positions, future_length.cpu(), clips.shape[1] - model.n_cond)

    def read(self, model: KEYIN, clips: Tensor, future_length: Tensor) -> PosteriorRead:
        """What the rule reads of ``model`` on the clips (:func:`keyin.decode.rules.read_posterior`).

        Raises:
            ValueError: the rule needs boundary scores and the model has no offset evidence.
        """
        from keyin.decode.rules import read_posterior

        read = read_posterior(model, clips, future_length)
        if self.needs_boundary_scores and read.keys.boundary_scores is None:
            raise ValueError(f"rule {self.name!r} needs the boundary scores of offset_evidence")
        return read

    def decode(self, read: PosteriorRead, prices: Prices, pixel_weights: Tensor | None, costs: Tensor | None) -> list[list[int]]:
        """Per clip, the keyframe positions the rule reads off ``read`` (before any sequence end)."""
        raise NotImplementedError

    def kept_segments(self, read: PosteriorRead, prices: Prices) -> Tensor | None:
        """(B, N, S) bool, the segments the rule prices; None: every segment."""
        return None

    def runs_on(self, offset_evidence: bool) -> bool:
        """Whether a model with(out) offset evidence has what the rule reads."""
        return offset_evidence or not self.needs_boundary_scores


class Offsets(Rule):
    """The paper's readout (§3.9): the argmax offsets, positions by their sums; with offset evidence
    each δ^t reads the previous keyframe where the argmax offsets put it."""

    name = "offsets"
    cost_rank = 1
    adds_sequence_ends = False
    variant = True

    def decode(self, read: PosteriorRead, prices: Prices, pixel_weights: Tensor | None, costs: Tensor | None) -> list[list[int]]:
        from keyin.decode.offsets import offset_keyframes

        return offset_keyframes(read.keys.offset_probs, read.future_length)


class Boundaries(Rule):
    """The most likely keyframe set under LSTM_inf's per-frame boundary scores, within M gaps of at
    most S (:func:`keyin.decode.rules.boundary_keyframes`)."""

    name = "boundaries"
    cost_rank = 0
    needs_boundary_scores = True
    variant = True

    def decode(self, read: PosteriorRead, prices: Prices, pixel_weights: Tensor | None, costs: Tensor | None) -> list[list[int]]:
        from keyin.decode.rules import boundary_keyframes

        predictor = read.model.predictor
        return boundary_keyframes(read.keys.boundary_scores, read.future_length.cpu(), predictor.n_keyframes,
                                  predictor.max_offset)


class Map(Rule):
    """The exact best segmentation under the frozen interpolator's pixel BCE with ``keyframe_cost``
    per keyframe (or each clip's knee count for :data:`keyin.decode.prices.KNEE`, label-free), plus ``boundary_weight``
    times the boundary scores where there are any (:func:`keyin.decode.rules.map_keyframes`)."""

    name = "map"
    cost_rank = 3
    reads_segment_costs = True
    variant = True

    def decode(self, read: PosteriorRead, prices: Prices, pixel_weights: Tensor | None, costs: Tensor | None) -> list[list[int]]:
        from keyin.decode.rules import map_keyframes

        model = read.model
        return map_keyframes(
            model.interpolator, model.decoder, read.embeddings[:, model.n_cond - 1 :], read.clips[:, model.n_cond :].flatten(2),
            read.future_length, model.predictor.n_keyframes, prices.keyframe_cost, self.prior(read), prices.boundary_weight,
            weights=pixel_weights, costs=costs, keep=self.kept_segments(read, prices),
        )

    def prior(self, read: PosteriorRead) -> Tensor | None:
        """(B, N) the boundary logits weighed in as a prior, None for the interpolation cost alone."""
        return read.keys.boundary_scores


class MapPruned(Map):
    """``map`` whose keyframes must have a boundary logit ≥ ``candidate_logit``: only the segments
    between such frames are rendered (:func:`keyin.decode.rules.candidate_keep`)."""

    name = "map_pruned"
    cost_rank = 2
    needs_boundary_scores = True
    prunes_segments = True
    variant = False

    def kept_segments(self, read: PosteriorRead, prices: Prices) -> Tensor:
        from keyin.decode.rules import candidate_keep

        return candidate_keep(read, prices.candidate_logit)


class Segmentation(Map):
    """``map`` without stage 2's boundary scores: stage 1's exact segmentation at the same price."""

    name = "segmentation"
    cost_rank = 4
    variant = False

    def prior(self, read: PosteriorRead) -> None:
        return None


# The rules by name; cost_rank orders them by their cost per kept frame: boundaries and offsets run the
# encoder and the posterior once (~0.3 ms per kept frame at Brownian size), map_pruned decodes only the
# segments between candidate keyframes (~1.2 ms), map every segment's frames (~7 ms in keyin-discover),
# segmentation as much (benchmarks/results/discover_speed_rules_brownian.md, discover_speed_map_pruned_brownian_1thread.md).
RULES: dict[str, Rule] = {rule.name: rule for rule in (Offsets(), Boundaries(), Map(), MapPruned(), Segmentation())}
PAPER_RULE = Offsets.name  # a stage-2 model's discovery unless its config says otherwise
EXACT_RULE = Map.name  # rule=auto's fallback and yardstick: the exact segmentation with the boundary prior


def rule_named(name: str) -> Rule:
    """The rule of :data:`RULES` called ``name``.

    Raises:
        ValueError: no rule is called that; the message names the choices.
    """
    if name not in RULES:
        raise ValueError(f"discovery must be one of {tuple(RULES)}, got {name!r}")
    return RULES[name]


def model_rule(discovery: str, offset_evidence: bool) -> Rule:
    """The rule a stage-2 model is configured to discover by (``discovery``), checked against what it has.

    Raises:
        ValueError: no rule is called that, or it reads boundary scores and the model has no offset evidence.
    """
    rule = rule_named(discovery)
    if not rule.runs_on(offset_evidence):
        raise ValueError(f"discovery={discovery!r} needs offset_evidence (the boundary scores)")
    return rule


def fastest_rule(val_f1: dict[str, float], tolerance: float = FAST_RULE_TOLERANCE) -> str:
    """The cheapest rule (by ``cost_rank``) whose validation F1 is at least :data:`EXACT_RULE`'s less
    ``tolerance`` (the exact rule itself when no cheaper one is); rules missing from ``val_f1`` are passed over.

    Raises:
        ValueError: ``val_f1`` has no score of the exact rule to compare with.
    """
    if EXACT_RULE not in val_f1:
        raise ValueError(f"fastest_rule compares with {EXACT_RULE}'s validation F1, which {sorted(val_f1)} lacks")
    by_cost = sorted(RULES.values(), key=lambda rule: rule.cost_rank)
    return next(rule.name for rule in by_cost if rule.name in val_f1 and val_f1[rule.name] >= val_f1[EXACT_RULE] - tolerance)
