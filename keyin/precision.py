"""Mixed precision made safe (``trainer.precision=bf16-mixed`` or ``16-mixed``): the losses and the
log-probability sums that meet them run in float32 whatever autocast chose for the networks."""

from __future__ import annotations

import functools
from typing import Any, Callable, TypeVar

import torch
from torch.utils._pytree import tree_map

F = TypeVar("F", bound=Callable[..., Any])
HALF = (torch.float16, torch.bfloat16)


def to_float32(value: Any) -> Any:
    """A half-precision tensor as float32; anything else as it is."""
    return value.float() if isinstance(value, torch.Tensor) and value.dtype in HALF else value


def in_float32(function: F) -> F:
    """Run ``function`` with autocast off on the CPU and the GPU and its half-precision tensor
    arguments (nested in lists, tuples and dicts too) in float32: in bf16 ``1 - 1e-6`` is 1 and a
    clamp at 1e-12 is 0, and sums of many log-probabilities lose their digits."""

    @functools.wraps(function)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with torch.autocast("cpu", enabled=False), torch.autocast("cuda", enabled=False):
            return function(*tree_map(to_float32, args), **tree_map(to_float32, kwargs))

    return wrapper  # type: ignore[return-value]
