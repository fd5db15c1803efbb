"""Running a module in eval mode for a moment (discovery, pictures) inside training."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from torch import nn


@contextmanager
def evaluating(module: nn.Module) -> Iterator[nn.Module]:
    """``module.eval()`` for the ``with`` block, then every submodule back to the mode it was in (so
    the parts a training module keeps frozen in eval mode stay so, whichever module is switched)."""
    modes = [(part, part.training) for part in module.modules()]
    module.eval()
    try:
        yield module
    finally:
        for part, training in modes:
            part.training = training
