"""Pretrained models shipped inside the package, loaded by name: ``ckpt=pretrained:<name>``.

``models.json`` names each model's file (in this folder) and its SHA-256; docs/models.md is the
model card (training command, scores). A shipped file is a keyin checkpoint slimmed for the
package (:func:`slim_checkpoint`): the weights, in half precision, and the run config; no optimizer
state, so it evaluates, discovers and plans but does not resume training.
"""

from __future__ import annotations

import io
import json
from pathlib import Path
from typing import TYPE_CHECKING, Any, Mapping

from keyin.errors import CheckpointError
from keyin.io import atomic_write_bytes, atomic_write_text, sha256_of

if TYPE_CHECKING:  # torch is imported where a checkpoint is read or written: naming a model does not load it
    import torch

PREFIX = "pretrained:"
FOLDER = Path(__file__).parent
REGISTRY = "models.json"
KEPT_ENTRIES = ("state_dict", "hyper_parameters", "keyin_config", "keyin_stage", "keyin_version", "global_step")


def registry(folder: Path = FOLDER) -> dict[str, dict[str, Any]]:
    """Name → {"file", "sha256", ...} of every model shipped in ``folder``."""
    path = folder / REGISTRY
    return json.loads(path.read_text()) if path.is_file() else {}


def is_pretrained(path: str | Path) -> bool:
    return str(path).startswith(PREFIX)


def resolve(path: str | Path, folder: Path = FOLDER) -> Path:
    """The file of ``pretrained:<name>`` (checked against its SHA-256); any other path unchanged.

    Raises:
        CheckpointError: an unknown name, a missing file or one whose hash differs.
    """
    if not is_pretrained(path):
        return Path(path)
    name, models = str(path)[len(PREFIX):], registry(folder)
    if name not in models:
        shipped = ", ".join(f"{PREFIX}{known}" for known in sorted(models)) or "none"
        raise CheckpointError(f"no pretrained model named '{name}'; this keyin ships {shipped} (docs/models.md)")
    file = folder / models[name]["file"]
    if not file.is_file() or sha256_of(file) != models[name]["sha256"]:
        raise CheckpointError(
            f"{file} (pretrained model '{name}') is missing or not the file keyin shipped (SHA-256 differs); "
            f"reinstall keyin (pip install --force-reinstall keyin)"
        )
    return file


def slim_checkpoint(checkpoint: Mapping[str, Any]) -> dict[str, Any]:
    """A checkpoint's entries that evaluation needs (:data:`KEPT_ENTRIES`), its floating-point weights
    in half precision (loading casts them back to the parameters' float32)."""
    slim = {key: checkpoint[key] for key in KEPT_ENTRIES if key in checkpoint}
    slim["state_dict"] = {
        name: value.half() if value.is_floating_point() else value for name, value in checkpoint["state_dict"].items()
    }
    return slim


def full_precision(state_dict: Mapping[str, torch.Tensor]) -> dict[str, torch.Tensor]:
    """A state dict with its half-precision tensors in float32 (a slimmed checkpoint's weights)."""
    import torch

    return {name: value.float() if value.dtype == torch.float16 else value for name, value in state_dict.items()}


def export(checkpoint: Mapping[str, Any], name: str, card: Mapping[str, Any], folder: Path = FOLDER) -> Path:
    """Write ``checkpoint`` slimmed as ``<folder>/<name>.ckpt`` and register it (with ``card``: the
    training command, the source checkpoint's hash, ...) in ``models.json``."""
    import torch

    buffer = io.BytesIO()
    torch.save(slim_checkpoint(checkpoint), buffer)
    folder.mkdir(parents=True, exist_ok=True)
    file = folder / f"{name}.ckpt"
    atomic_write_bytes(file, buffer.getvalue())
    models = registry(folder)
    models[name] = {**card, "file": file.name, "sha256": sha256_of(file), "bytes": file.stat().st_size}
    atomic_write_text(folder / REGISTRY, json.dumps(models, indent=1, sort_keys=True) + "\n")
    return file


def annotate(name: str, fields: Mapping[str, Any], folder: Path = FOLDER) -> None:
    """Add ``fields`` to the card of the shipped model ``name`` in ``models.json``.

    Raises:
        CheckpointError: no model of that name is shipped in ``folder``.
    """
    models = registry(folder)
    if name not in models:
        raise CheckpointError(f"no pretrained model named '{name}' in {folder / REGISTRY}")
    models[name] = {**models[name], **fields}
    atomic_write_text(folder / REGISTRY, json.dumps(models, indent=1, sort_keys=True) + "\n")


def recorded_rule(path: str | Path, folder: Path = FOLDER) -> dict[str, Any] | None:
    """The default rule recorded for ``pretrained:<name>`` (``{"rule", "val_f1_interior", ...}``), or None
    for any other checkpoint and for a shipped model without one."""
    if not is_pretrained(path):
        return None
    card = registry(folder).get(str(path)[len(PREFIX):], {})
    return card.get("default_rule")
