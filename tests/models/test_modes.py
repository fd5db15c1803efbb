"""Eval mode for a moment, and stage 1 frozen whatever mode stage 2 is switched to."""

import pytest
import torch

from keyin.models.modes import evaluating
from tests.planning.trained_models import keyframe_module


def test_evaluating_restores_the_mode_even_after_an_error():
    module = torch.nn.Sequential(torch.nn.Linear(2, 2), torch.nn.Dropout()).train()
    with evaluating(module):
        assert not module.training and not module[1].training
    assert module.training and module[1].training
    with pytest.raises(RuntimeError), evaluating(module):
        raise RuntimeError("inside")
    assert module.training


def test_stage2_in_train_mode_keeps_stage1_frozen_in_eval_mode():
    module = keyframe_module().train()
    for name in ("encoder", "decoder", "interpolator"):
        part = getattr(module.model, name)
        assert not part.training and not any(p.requires_grad for p in part.parameters()), name
    assert module.model.predictor.training and all(p.requires_grad for p in module.model.predictor.parameters())


def test_evaluating_the_model_alone_keeps_stage1_frozen():
    """A reader switches a training module's model, not the module: stage 1 must come back in eval mode."""
    module = keyframe_module().train()
    with evaluating(module.model):
        assert not module.model.predictor.training
    assert module.model.predictor.training and not module.model.encoder.training
