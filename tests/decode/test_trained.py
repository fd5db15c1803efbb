"""A stage-2 checkpoint's reader, built without Lightning, finds the keyframes the LightningModule's reader finds."""

import dataclasses
import inspect

import torch

from keyin.decode.teacher import TeacherConfig
from keyin.decode.trained import KeyframeReader
from keyin.lit.keyframes import KeyframeModule
from keyin.decode.flat_hparams import typed_keyframe_arguments
from keyin.losses.soft_keyframe import SoftLossConfig
from keyin.models.config import KEYINConfig, PredictorConfig
from tests.lit.tiny_models import batch, stage1, stage2


def test_a_flat_checkpoint_without_the_later_options_upgrades_to_the_typed_defaults():
    """The flat hyper-parameters' defaults (keyin.decode.flat_hparams.FLAT_DEFAULTS, for checkpoints saved before
    an option existed) are the typed module's and configs' defaults."""
    flat = dict(stage1=dict(stage1("ours").hparams), n_keyframes=2, latent_dim=2, lstm_hidden=8, lstm_layers=1,
                attn_scale=True, offset_mode="predicted", fixed_offset=None, beta_ke=1.0, beta_ki=0.0, beta_kl=0.05,
                normalize_key_targets=True, lr=1e-3)
    typed = typed_keyframe_arguments(flat)
    defaults = {name: p.default for name, p in inspect.signature(KeyframeModule.__init__).parameters.items()}
    kept = ("discovery", "map_keyframe_cost", "map_boundary_weight", "map_candidate_logit", "frozen")
    assert {key: typed[key] for key in kept} == {key: defaults[key] for key in kept}
    assert typed["teacher"] == dataclasses.asdict(TeacherConfig())
    assert typed["loss"] == dataclasses.asdict(SoftLossConfig(1.0, 0.0, 0.05))
    net = KEYINConfig.from_dict(typed["net"])
    assert net.predictor == PredictorConfig(2, 2, 8, 1)
    assert (net.delta_input, net.gumbel_offsets, net.interpolate_from) == ("soft", False, "predicted")


def test_a_checkpoints_reader_discovers_as_the_training_modules_by_every_rule():
    lightning = stage2("ours", offset_evidence=True, discovery="map").eval()
    plain, trained = KeyframeReader.from_hparams(**lightning.hparams), lightning.reader()
    plain.load_state_dict(lightning.state_dict())
    clips = batch()
    for rule in ("offsets", "boundaries", "map", "map_pruned", "segmentation"):
        assert plain.discover(clips["frames"], clips["future_length"], rule) == trained.discover(
            clips["frames"], clips["future_length"], rule), rule
    torch.testing.assert_close(plain.keyframe_probabilities(clips["frames"], clips["future_length"]),
                               trained.keyframe_probabilities(clips["frames"], clips["future_length"]))
