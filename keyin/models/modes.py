"""Running a module in eval mode for a moment (discovery, pictures) inside training."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from torch import nn


@contextmanager
def evaluating(module: nn.Module) -> Iterator[nn.Module]:
    """``module.eval()`` for the ``with`` block, then back to the mode it was in (through
    ``module.train``, so a module that keeps parts frozen re-freezes them)."""
    was_training = module.training
    module.eval()
    try:
        yield module
    finally:
        module.train(was_training)
