"""Safe checkpoint loading and the run config that travels inside every checkpoint, without
Lightning: keyin-eval and keyin-discover load a trained model with torch alone (keyin.lit.checkpoints
adds what training needs)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, Mapping

import torch

from keyin.errors import CheckpointError
from keyin.decode.flat_hparams import upgrade_keyframe_hparams
from keyin.legacy import current_model_name, upgrade_state_dict
from keyin.models.config import KEYINConfig
from keyin.models.keyin import STAGE1
from keyin.models.state import sub_state_dict
from keyin.pretrained import full_precision, resolve

CONFIG_KEY = "keyin_config"
STAGE_KEY = "keyin_stage"
VERSION_KEY = "keyin_version"
PASS_A_CHECKPOINT = "pass one that keyin-train wrote (<run dir>/checkpoints/<stage>/last.ckpt, or <run dir>/best)"
BEST, LAST = "best", "last"  # each stage's checkpoints/<stage>/{best,last}.ckpt (keyin.lit.run.stage_checkpoints)
FINAL_STAGES = ("keyframes", "surprise", "tap", "frames", "interpolator")  # a run's model: its last stage first


def saved_model_name(checkpoint: Mapping[str, Any]) -> str | None:
    """The ``model.name`` a checkpoint was trained as, in this version's names (a checkpoint of keyin
    0.1, which has no version entry, says ``keyin`` for today's ``keyin_plus``)."""
    name = (checkpoint.get(CONFIG_KEY) or {}).get("model", {}).get("name")
    return current_model_name(name, VERSION_KEY in checkpoint)


STAGE_CHECKPOINTS = {
    "interpolator": "the stage-1 checkpoint (checkpoints/interpolator/last.ckpt)",
    "keyframes": "a stage-2 checkpoint (checkpoints/keyframes/last.ckpt)",
    "frames": "a frame autoencoder's checkpoint (keyin-train model=frame_autoencoder: checkpoints/frames/last.ckpt)",
}


def run_checkpoint(path: Path) -> Path:
    """``<run dir>/best`` or ``<run dir>/last``: that checkpoint of the run's model (its last stage:
    ``checkpoints/keyframes/best.ckpt`` of a KEYIN run); any other path unchanged."""
    if path.name not in (BEST, LAST) or path.exists():
        return path
    stages = [path.parent / "checkpoints" / stage / f"{path.name}.ckpt" for stage in FINAL_STAGES]
    return next((file for file in stages if file.is_file()), path)


def best_of(folder: Path) -> dict[str, Any] | None:
    """The monitored metric, value and step of ``<folder>/best.ckpt`` (a stage's checkpoint folder), None without one."""
    path = Path(folder) / f"{BEST}.ckpt"
    if not path.is_file():
        return None
    checkpoint = torch.load(path, map_location="cpu", weights_only=True, mmap=True)
    state = next(state for key, state in checkpoint["callbacks"].items() if key.startswith("ModelCheckpoint") and state["monitor"])
    return {"monitor": state["monitor"], "value": float(state["best_model_score"]), "step": checkpoint["global_step"]}


def load_checkpoint(path: str | Path, stage: str | None = None) -> dict[str, Any]:
    """Load a keyin checkpoint without running any pickled code (``weights_only=True``).

    Args:
        path: a checkpoint file, ``<run dir>/best`` or ``<run dir>/last`` (:func:`run_checkpoint`), or
            ``pretrained:<name>`` for one shipped with keyin (:mod:`keyin.pretrained`).
        stage: the stage to insist on ("interpolator", "keyframes", "surprise", "tap", "frames"); None accepts any.
    Raises:
        CheckpointError: missing file, unsafe or foreign content, or another stage.
    """
    path = run_checkpoint(resolve(path))
    if not path.is_file():
        raise CheckpointError(f"checkpoint {path} does not exist; pass the path of a keyin checkpoint")
    try:
        checkpoint = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as err:  # unpickling refuses anything but tensors and primitives
        raise CheckpointError(
            f"{path} is not a loadable keyin checkpoint ({type(err).__name__}: "
            f"{str(err).splitlines()[0][:200]}); it may be corrupt or carry code, which keyin refuses: "
            f"{PASS_A_CHECKPOINT}"
        ) from None
    if not isinstance(checkpoint, dict) or STAGE_KEY not in checkpoint:
        raise CheckpointError(f"{path} is not a keyin checkpoint (no '{STAGE_KEY}' entry); {PASS_A_CHECKPOINT}")
    checkpoint["state_dict"] = full_precision(upgrade_state_dict(checkpoint["state_dict"], checkpoint[STAGE_KEY]))
    if checkpoint[STAGE_KEY] == "keyframes":  # flat hyper-parameters before the typed configs
        checkpoint["hyper_parameters"] = upgrade_keyframe_hparams(checkpoint["hyper_parameters"])
    if stage is not None and checkpoint[STAGE_KEY] != stage:
        raise CheckpointError(
            f"{path} is a '{checkpoint[STAGE_KEY]}' checkpoint but a '{stage}' one is needed"
            + f"; pass {STAGE_CHECKPOINTS.get(stage, f'checkpoints/{stage}/last.ckpt of a {stage} run')}"
        )
    return checkpoint


def load_stage1(path: str | Path) -> dict[str, Any]:
    """The stage-1 checkpoint that stage 2 starts from, or the frozen stage 1 inside a stage-2
    checkpoint (``pretrained:<name>`` included): ``hyper_parameters`` (the interpolator module's; of a
    stage 2, its stage-1 sizes: :meth:`keyin.models.config.KEYINConfig.stage1_hparams`) and ``state_dict``
    of the interpolator module, so that several stage 2s can be trained on one shipped stage 1.

    Raises:
        CheckpointError: as :func:`load_checkpoint`, or a checkpoint of neither stage.
    """
    checkpoint = load_checkpoint(path)
    if checkpoint[STAGE_KEY] == "interpolator":
        return checkpoint
    if checkpoint[STAGE_KEY] != "keyframes":
        raise CheckpointError(
            f"{path} is a '{checkpoint[STAGE_KEY]}' checkpoint; stage 2 starts from {STAGE_CHECKPOINTS['interpolator']} "
            f"or from the stage 1 inside {STAGE_CHECKPOINTS['keyframes']}"
        )
    model = sub_state_dict(checkpoint["state_dict"], "model.")
    networks = {name: value for name, value in model.items() if name.startswith(tuple(f"{network}." for network in STAGE1))}
    stage1 = KEYINConfig.from_dict(checkpoint["hyper_parameters"]["net"]).stage1_hparams()
    return {"hyper_parameters": stage1, "state_dict": networks}


def parameter_shapes(state_dict: Mapping[str, Any]) -> dict[str, tuple[int, ...]]:
    """Name → shape of every tensor of a state dict."""
    return {name: tuple(value.shape) for name, value in state_dict.items()}
