"""Where a command runs its model: ``device=auto|cpu|cuda|cuda:N``, and batch sizes that fill it."""

from __future__ import annotations

import re

import torch

from keyin.errors import ConfigError

AUTO = "auto"  # the first GPU when torch sees one, else the CPU
CHOICES = "device=auto|cpu|cuda|cuda:N"


def choose_device(name: str) -> torch.device:
    """The device ``device=`` names; ``auto`` is ``cuda:0`` where torch sees a GPU, else the CPU.

    Raises:
        ConfigError: an unknown name, or a GPU this machine does not have.
    """
    name = str(name).strip().lower()
    if name == AUTO:
        return torch.device("cuda:0" if torch.cuda.is_available() else "cpu")
    if not re.fullmatch(r"cpu|cuda(:\d+)?", name):
        raise ConfigError(f"device={name} is not a device; choose {CHOICES}")
    device = torch.device(name)
    if device.type == "cuda":
        count = torch.cuda.device_count() if torch.cuda.is_available() else 0
        if count == 0:
            raise ConfigError(f"device={name}: this machine has no GPU that torch can use; pass device=auto or device=cpu")
        if (device.index or 0) >= count:
            raise ConfigError(f"device={name}: this machine has {count} GPU(s), cuda:0..cuda:{count - 1}; "
                              f"pass one of those, device=auto or device=cpu")
        device = torch.device("cuda", device.index or 0)
    return device


def batch_size_on(device: torch.device, value: int | None, cpu: int, gpu: int) -> int:
    """``value``, or where it is null the default of the device's kind (``cpu`` or ``gpu``)."""
    if value is not None:
        return value
    return gpu if device.type == "cuda" else cpu


def device_record(device: torch.device) -> dict[str, str | None]:
    """What metrics.json and keyframes.json say about the device: ``device`` (``cpu``, ``cuda:0``)
    and ``device_name`` (the GPU's name, None on the CPU)."""
    name = torch.cuda.get_device_name(device) if device.type == "cuda" else None
    return {"device": str(device), "device_name": name}
