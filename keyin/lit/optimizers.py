"""The optimizers of the training stages (paper section 4: Adam, β1 = 0.9, β2 = 0.999).

Stage 2 takes its optimizer as a partial of the parameters (``optimizer: {_target_: torch.optim.Adam,
_partial_: true, lr: ...}``, as lightning-hydra-template passes it); its checkpoint keeps the partial
as that plain dict (:func:`optimizer_spec`), which :func:`optimizer_partial` reads back.
"""

from __future__ import annotations

import functools
from typing import Any, Callable, Iterable, Mapping

import torch
from torch import nn

from keyin.models.config import PAPER_BETAS

OptimizerPartial = Callable[[Iterable[nn.Parameter]], torch.optim.Optimizer]


def adam(module: nn.Module, lr: float) -> torch.optim.Adam:
    """Adam over the parameters of ``module`` that train (frozen networks left out), at ``lr``."""
    return torch.optim.Adam(trained_parameters(module), lr=lr, betas=PAPER_BETAS)


def trained_parameters(module: nn.Module) -> list[nn.Parameter]:
    """The parameters of ``module`` that train (frozen networks left out)."""
    return [p for p in module.parameters() if p.requires_grad]


def optimizer_spec(optimizer: OptimizerPartial | Mapping[str, Any]) -> dict[str, Any]:
    """A plain dict (``_target_``, ``_partial_`` and the keyword arguments) of a partial of a
    ``torch.optim`` class, or of such a dict."""
    if isinstance(optimizer, Mapping):
        return {**optimizer, "_partial_": True}
    func = getattr(optimizer, "func", None)
    if not isinstance(optimizer, functools.partial) or optimizer.args or getattr(torch.optim, func.__name__, None) is not func:
        raise ValueError(f"the optimizer must be a partial of a torch.optim class with keyword arguments, got {optimizer!r}")
    keywords = {key: list(value) if isinstance(value, tuple) else value for key, value in optimizer.keywords.items()}
    return {"_target_": f"torch.optim.{func.__name__}", "_partial_": True, **keywords}


def optimizer_partial(spec: Mapping[str, Any]) -> OptimizerPartial:
    """The optimizer partial of a spec (:func:`optimizer_spec`); only ``torch.optim`` classes."""
    module, _, name = spec["_target_"].rpartition(".")
    if module != "torch.optim" or not isinstance(getattr(torch.optim, name, None), type):
        raise ValueError(f"the optimizer must be a torch.optim class, got {spec['_target_']!r}")
    return functools.partial(getattr(torch.optim, name), **{key: value for key, value in spec.items() if not key.startswith("_")})
