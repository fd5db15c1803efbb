"""compile=true of keyin-eval / keyin-discover: the frame networks the discovery rules call are compiled
in place, and the checkpoint's parameter names stay the same."""

from keyin.lit.registry import load_trained_module
from keyin.lit.run import compile_frame_networks


def test_the_frame_networks_of_a_stage2_model_are_compiled_in_place():
    module, _ = load_trained_module("pretrained:brownian")
    names = list(module.state_dict())
    assert compile_frame_networks(module) == ["encoder", "decoder", "interpolator"]
    assert list(module.state_dict()) == names
    assert all(getattr(module.model, name)._compiled_call_impl is not None for name in ("encoder", "decoder", "interpolator"))
    assert module.model.predictor._compiled_call_impl is None  # the keyframe predictor runs as it was
