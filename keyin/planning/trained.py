"""The trained models behind the learned high-level planners (KEYIN, Jumpy, TAP): checked and
loaded once per process, and images converted between the tasks' uint8 and the models' [0, 1].

``keyin-plan`` builds the planner in its main process, which loads the checkpoint there: a missing
or wrong one stops the run with one error line before any task. The runner pickles the planner into
every task it hands a spawn worker; the planner holds only the checkpoint's path and its numbers,
and :func:`trained_module` loads the model at a process's first task and keeps it for the process's
life (a cache keyed by its arguments), on ``device`` (``auto``: the GPU where there is one), with
``torch_threads`` intra-op threads (1: the workers already use every core).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from typing import ClassVar

import numpy as np
import torch

from keyin.devices import choose_device
from keyin.errors import CheckpointError, DatasetFormatError
from keyin.lit.registry import load_trained_module
from keyin.pretrained import resolve


@functools.cache
def trained_module(
    checkpoint: str, stage: str, model: str, dataset: str, train_command: str, threads: int, device: str = "cpu"
) -> torch.nn.Module:
    """The module of ``checkpoint``, in eval mode on ``device`` (``device=``'s choices); loaded once per process.

    Args:
        stage: the training stage it must hold ("keyframes", "tap").
        model, dataset: the ``model=`` and ``dataset=`` it must have been trained with.
        train_command: the keyin-train command that makes it, for the error messages.
        threads: torch's intra-op threads in this process.
    Raises:
        ConfigError: a device this machine does not have.
        CheckpointError: a missing or unloadable file, another stage, model or dataset.
    """
    fix = (
        f"the planner needs a model={model} dataset={dataset} checkpoint: make it with `{train_command}` or "
        f"pass planner.checkpoint=<its path>"
    )
    try:
        path = resolve(checkpoint)  # a path, or pretrained:<name>
        if not path.is_file():
            raise CheckpointError(f"checkpoint {path} does not exist")
        module, config = load_trained_module(path, stage)
    except CheckpointError as err:
        raise CheckpointError(f"{err}; {fix}") from None
    saved = {key: (config.get(key) or {}).get("name") for key in ("model", "dataset")}
    if saved != {"model": model, "dataset": dataset}:
        raise CheckpointError(f"{path} holds a model={saved['model']} dataset={saved['dataset']} checkpoint; {fix}")
    torch.set_num_threads(threads)
    return module.to(choose_device(device)).eval()


@dataclass(frozen=True)
class TrainedPlanner:
    """What every learned high-level planner is configured with (``conf/planner/<name>.yaml``).

    Attributes:
        checkpoint: path of the trained model's ``last.ckpt``, or ``pretrained:<name>`` (:mod:`keyin.pretrained`).
        model, dataset: the ``model=`` and ``dataset=`` it must have been trained with.
        train_command: the keyin-train command that makes it (named when it is missing or wrong).
        torch_threads: torch's intra-op threads in each planning process.
        device: where the model plans (``device=auto|cpu|cuda|cuda:N``).
    """

    stage: ClassVar[str]  # the training stage the checkpoint holds

    checkpoint: str
    model: str
    dataset: str
    train_command: str
    torch_threads: int = 1
    device: str = "cpu"

    def __post_init__(self) -> None:
        self.module()  # a missing or wrong checkpoint stops keyin-plan before its first task

    def module(self) -> torch.nn.Module:
        """The trained module, loaded at this process's first call."""
        return trained_module(
            self.checkpoint, self.stage, self.model, self.dataset, self.train_command, self.torch_threads, self.device
        )


def images_to_tensor(images: np.ndarray, shape: tuple[int, int, int]) -> torch.Tensor:
    """(..., H, W, C) uint8 images -> (..., C, H, W) float32 in [0, 1].

    Args:
        shape: the model's (C, H, W).
    Raises:
        DatasetFormatError: the images have another size or channel count.
    """
    channels, height, width = shape
    if images.shape[-3:] != (height, width, channels):
        raise DatasetFormatError(
            f"the planning tasks' images are {'x'.join(map(str, images.shape[-3:]))} (H x W x C) but the "
            f"planner's model takes {height}x{width}x{channels}; use a checkpoint trained on the tasks' images"
        )
    return torch.from_numpy(np.ascontiguousarray(images)).movedim(-1, -3).float() / 255.0


def tensor_to_images(probs: torch.Tensor) -> np.ndarray:
    """(..., C, H, W) pixel probabilities -> (..., H, W, C) uint8 images."""
    return (probs.clamp(0, 1) * 255).round().to(torch.uint8).movedim(-3, -1).cpu().numpy()


def conditioning_frames(
    start: np.ndarray, shape: tuple[int, int, int], n_cond: int, device: torch.device | str = "cpu"
) -> torch.Tensor:
    """(1, n_cond, C, H, W) on ``device``: the (H, W, C) uint8 start image as every conditioning frame
    of a model whose frames are ``shape`` = (C, H, W) (pushing has one conditioning frame)."""
    frames = images_to_tensor(start, shape).to(device)
    return frames.expand(1, n_cond, *frames.shape)
