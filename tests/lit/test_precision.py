"""Mixed precision (``trainer.precision=bf16-mixed`` / ``16-mixed``): every model's training step runs
under autocast without a dtype error, and its bf16 loss is the float32 one within 3 % (bf16 keeps
about 3 significant digits; the losses and log-probability sums run in float32, keyin/precision.py)."""

import pytest
import torch

from keyin.precision import in_float32
from tests.lit.tiny_models import MODELS, batch

BF16_REL = 0.03  # relative tolerance of a bf16-autocast loss against the float32 one


def training_loss(name: str, dtype: torch.dtype | None) -> torch.Tensor:
    """One training step's loss of a fresh model (same seed, same draws), under CPU autocast to ``dtype``."""
    module = MODELS[name]()
    torch.manual_seed(0)
    with torch.autocast("cpu", dtype=dtype or torch.float32, enabled=dtype is not None):
        loss = module.training_step(batch(), 0)
    loss.backward()
    return loss.detach()


@pytest.mark.filterwarnings("ignore:You are trying to `self.log\\(\\)`")
@pytest.mark.parametrize("name", MODELS)
def test_every_model_trains_in_bf16_and_fp16_autocast_near_its_float32_loss(name):
    full, bf16, fp16 = (training_loss(name, dtype) for dtype in (None, torch.bfloat16, torch.float16))
    assert torch.isfinite(full) and torch.isfinite(bf16) and torch.isfinite(fp16)
    assert float(bf16) == pytest.approx(float(full), rel=BF16_REL)


def test_float32_holds_what_half_precision_loses():
    probs = torch.tensor([0.0, 1.0, 1e-7], dtype=torch.float16)  # fp16: 1e-12 rounds to 0

    @in_float32
    def entropy(p):
        return -(p * p.clamp_min(1e-12).log()).sum()

    with torch.autocast("cpu", dtype=torch.float16):
        assert torch.isfinite(entropy(probs)) and entropy(probs).dtype == torch.float32
    assert torch.isnan(-(probs * probs.clamp_min(1e-12).log()).sum())  # the clamp in fp16: 0 · log 0
