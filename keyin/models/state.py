"""Parts of a state dict: the tensors of one network inside a larger model's."""

from __future__ import annotations

from typing import Any, Mapping


def sub_state_dict(state_dict: Mapping[str, Any], prefix: str) -> dict[str, Any]:
    """The entries of ``state_dict`` under ``prefix`` (e.g. ``"model.encoder."``), their keys without it."""
    return {key[len(prefix) :]: value for key, value in state_dict.items() if key.startswith(prefix)}
