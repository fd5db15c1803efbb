"""The flat stage-2 hyper-parameters (checkpoints saved before the typed configs, and the keys of
``model.keyframes`` in conf/model/keyin.yaml) in typed terms, without Lightning: :meth:`keyin.decode.trained.KeyframeReader.from_hparams`,
:mod:`keyin.checkpoints` and :class:`keyin.lit.keyframes.KeyframeModule` read them through here."""

from __future__ import annotations

import dataclasses
from typing import Any, Mapping

from keyin.decode.prices import MAP_CANDIDATE_LOGIT
from keyin.decode.registry import PAPER_RULE
from keyin.decode.teacher import TeacherConfig
from keyin.losses.soft_keyframe import SoftLossConfig
from keyin.models.config import KEYINConfig, PredictorConfig, adam_spec, picked

# The flat stage-2 hyper-parameters that have a default: what a checkpoint saved before one was added did.
FLAT_DEFAULTS: dict[str, Any] = {
    "teacher_weight": 0.0, "teacher_clips": 0, "offset_evidence": False, "discovery": PAPER_RULE,
    "teacher_keyframe_cost": 0.0, "teacher_chain": False, "teacher_leaves": False, "map_keyframe_cost": 120.0,
    "map_boundary_weight": 10.0, "map_candidate_logit": MAP_CANDIDATE_LOGIT, "delta_input": "soft",
    "loss_reduction": "sum", "entropy_bonus": 0.0, "entropy_bonus_steps": 0, "gumbel_offsets": False,
    "frozen": "stage1", "interpolate_from": "predicted",
}
DISCOVERY_ARGUMENTS = ("discovery", "map_keyframe_cost", "map_boundary_weight", "map_candidate_logit")


def typed_keyframe_arguments(flat: Mapping[str, Any]) -> dict[str, Any]:
    """:class:`keyin.lit.keyframes.KeyframeModule`'s arguments, configs as plain dicts, of the flat
    stage-2 hyper-parameters: those checkpoints saved before the typed configs hold, and the keys of
    ``model.keyframes`` (conf/model/keyin.yaml) with the stage-1 module's hyper-parameters as ``stage1``.

    Flat → typed: ``stage1`` (the frame model, interpolator and clip sizes), ``n_keyframes``,
    ``latent_dim``, ``lstm_*``, ``attn_scale``, ``offset_mode``, ``fixed_offset``, ``offset_evidence``,
    ``delta_input``, ``gumbel_offsets``, ``interpolate_from`` → ``net`` (:class:`KEYINConfig`);
    ``beta_*``, ``normalize_key_targets``, ``loss_reduction``, ``entropy_bonus*`` → ``loss``
    (:class:`SoftLossConfig`); ``teacher_*`` → ``teacher`` (:class:`TeacherConfig`); ``lr`` → ``optimizer``
    (the paper's Adam); the discovery rule's four and ``frozen`` as they are.
    """
    values = {**FLAT_DEFAULTS, **flat}
    forward = {key: values[key] for key in ("delta_input", "gumbel_offsets", "interpolate_from")}
    net = KEYINConfig.of_stage1(values["stage1"], picked(PredictorConfig, values), **forward)
    loss = SoftLossConfig(
        values["beta_ke"], values["beta_ki"], values["beta_kl"], values["normalize_key_targets"], values["loss_reduction"],
        values["entropy_bonus"], values["entropy_bonus_steps"],
    )
    teacher = TeacherConfig(values["teacher_weight"], values["teacher_clips"], values["teacher_keyframe_cost"],
                            values["teacher_chain"], values["teacher_leaves"])
    return {
        "net": dataclasses.asdict(net), "loss": dataclasses.asdict(loss), "optimizer": adam_spec(values["lr"]),
        "teacher": dataclasses.asdict(teacher), **{key: values[key] for key in (*DISCOVERY_ARGUMENTS, "frozen")},
    }


def upgrade_keyframe_hparams(hparams: Mapping[str, Any]) -> dict[str, Any]:
    """A stage-2 checkpoint's hyper-parameters in this version's terms: flat ones (a ``stage1`` entry;
    :func:`typed_keyframe_arguments`) upgraded, typed ones as they are."""
    return typed_keyframe_arguments(hparams) if "stage1" in hparams else dict(hparams)
