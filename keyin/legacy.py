"""What keyin 0.1 saved, in this version's terms: state dicts of the old layout and old model names."""

from __future__ import annotations

from typing import Any, Mapping

from keyin import RENAMED_SINCE_0_1

# Stage → the networks its LightningModule once kept at the top level and its model (``module.model``)
# holds now: keyin 0.1's stage 2 (a KEYIN model since 0.2) and the Surprise baseline (an SVG model).
MODEL_NETWORKS = {
    "keyframes": ("encoder.", "decoder.", "interpolator.", "predictor."),
    "surprise": ("encoder.", "decoder.", "core."),
}


# Parameters renamed since they were saved: Static's offset logits became its offset head's (issue 49).
RENAMED_PARAMETERS = {"model.predictor.static_offset_logits": "model.predictor.offset_head.logits"}


def upgrade_state_dict(state_dict: Mapping[str, Any], stage: str) -> dict[str, Any]:
    """A state dict of ``stage`` in this version's layout (``model.encoder.*``, ...): one in the old
    layout (``encoder.*``, ...; :data:`MODEL_NETWORKS`) is moved under ``model.`` and the parameters
    of :data:`RENAMED_PARAMETERS` take their new names; one of today, or of a stage without a model,
    is returned as it is."""
    networks = MODEL_NETWORKS.get(stage, ())
    moved = {f"model.{name}" if name.startswith(networks) else name: value for name, value in state_dict.items()}
    return {RENAMED_PARAMETERS.get(name, name): value for name, value in moved.items()}


def current_model_name(name: str | None, versioned: bool) -> str | None:
    """A saved ``model.name`` in this version's names: a checkpoint without a version entry is keyin
    0.1's, whose ``keyin`` is today's ``keyin_plus``."""
    return name if versioned else RENAMED_SINCE_0_1.get(name, name)
