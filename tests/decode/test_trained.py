"""A stage-2 checkpoint built without Lightning finds the keyframes the LightningModule finds."""

import inspect

import torch

from keyin.decode.trained import INFERENCE_DEFAULTS, TrainedKeyframes
from keyin.lit.keyframes import KeyframeModule
from tests.lit.tiny_models import batch, stage2


def test_the_inference_defaults_are_the_training_modules():
    defaults = {name: p.default for name, p in inspect.signature(KeyframeModule.__init__).parameters.items()}
    assert {name: defaults[name] for name in INFERENCE_DEFAULTS} == INFERENCE_DEFAULTS


def test_the_plain_module_discovers_as_the_lightning_module_by_every_rule():
    trained = stage2("ours", offset_evidence=True, discovery="map").eval()
    plain = TrainedKeyframes(**trained.hparams)
    plain.load_state_dict(trained.state_dict())
    clips = batch()
    for rule in ("offsets", "boundaries", "map", "map_pruned", "segmentation"):
        assert plain.discover(clips["frames"], clips["future_length"], rule) == trained.discover(
            clips["frames"], clips["future_length"], rule), rule
    torch.testing.assert_close(plain.keyframe_probabilities(clips["frames"], clips["future_length"]),
                               trained.keyframe_probabilities(clips["frames"], clips["future_length"]))
