"""The one optimizer every training stage uses (paper section 4: Adam, β1 = 0.9, β2 = 0.999)."""

from __future__ import annotations

import torch
from torch import nn


def adam(module: nn.Module, lr: float) -> torch.optim.Adam:
    """Adam over the parameters of ``module`` that train (frozen networks left out), at ``lr``."""
    return torch.optim.Adam([p for p in module.parameters() if p.requires_grad], lr=lr, betas=(0.9, 0.999))
