"""compile=true of keyin-eval / keyin-discover: the frame networks the discovery rules call are compiled
in place, and the checkpoint's parameter names stay the same; keyin-train's compile=true the same way."""

import torch

from keyin.lit.registry import load_trained_module
from keyin.lit.run import compile_frame_networks, compile_in_place


def test_the_frame_networks_of_a_stage2_model_are_compiled_in_place():
    module, _ = load_trained_module("pretrained:brownian")
    names = list(module.state_dict())
    assert compile_frame_networks(module) == ["encoder", "decoder", "interpolator"]
    assert list(module.state_dict()) == names
    assert all(getattr(module.model, name)._compiled_call_impl is not None for name in ("encoder", "decoder", "interpolator"))
    assert module.model.predictor._compiled_call_impl is None  # the keyframe predictor runs as it was


def test_training_compiles_every_child_network_and_keeps_the_names():
    """compile=true of keyin-train: each child network of the module, the one way that discovery uses too."""
    holder = torch.nn.Module()
    holder.encoder, holder.head = torch.nn.Linear(2, 3), torch.nn.Sequential(torch.nn.Linear(3, 1))
    names = list(holder.state_dict())
    assert compile_in_place(holder) == ["encoder", "head"]
    assert list(holder.state_dict()) == names
    assert all(network._compiled_call_impl is not None for network in holder.children())
    assert compile_in_place(torch.nn.Module(), ["encoder"]) == []
