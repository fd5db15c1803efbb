"""Every shipped (keyin/pretrained/) and committed (models/) stage-2 checkpoint, saved with the flat
hyper-parameters of before the typed configs, loads through Lightning and through keyin.decode.trained
as the same model, which runs; and a checkpoint of today's typed hyper-parameters loads again with
``KeyframeModule.load_from_checkpoint`` and no other argument."""

import dataclasses
import inspect
import json
from pathlib import Path

import lightning as L
import pytest
import torch

from keyin.decode.trained import KeyframeReader
from keyin.lit.keyframes import KeyframeModule
from keyin.lit.registry import load_trained_module, load_training_module
from keyin.models.config import KEYINConfig
from keyin.pretrained import FOLDER, registry
from tests.lit.tiny_models import stage2

ROOT = Path(__file__).parents[2]
SHIPPED = [FOLDER / card["file"] for card in registry().values()]
# the committed stage 2s of before the typed configs (models/in_progress/ carries today's jobs, typed: tests/test_carry.py)
COMMITTED = [ROOT / entry["path"] for entry in json.loads((ROOT / "models" / "manifest.json").read_text())["models"]
             if entry["stage"] == "keyframes" and not entry["path"].startswith("models/in_progress/")]


def lightning_file(path: Path, folder: Path) -> Path:
    """A copy of a slimmed checkpoint that Lightning's loader reads (it asks for its version entry)."""
    checkpoint = torch.load(path, map_location="cpu", weights_only=True)
    checkpoint["pytorch-lightning_version"] = L.__version__
    copy = folder / path.name
    torch.save(checkpoint, copy)
    return copy


def outputs(module: KeyframeReader) -> dict[str, torch.Tensor]:
    """The posterior mean forward (z = 0 where the interpolator is stochastic) of fixed random clips."""
    config = module.config
    torch.manual_seed(0)
    size, channels = config.frames.image_size, config.frames.channels
    clips = torch.rand(2, config.n_cond + config.n_future, channels, size, size)
    lengths = torch.tensor([config.n_future, config.n_future - 3])
    module.eval()
    torch.manual_seed(1)
    with torch.no_grad():
        out = module.model(clips, lengths, sample=False)
    found = module.discover(clips, lengths, discovery="offsets")
    return {key: value for key, value in out.items() if value is not None} | {"found": torch.tensor(sum(found, []))}


@pytest.mark.parametrize("path", SHIPPED + COMMITTED, ids=lambda path: str(path.relative_to(ROOT)))
def test_every_shipped_and_committed_stage_2_loads_through_lightning_and_without(path, tmp_path):
    saved = torch.load(path, map_location="cpu", weights_only=True)["hyper_parameters"]
    assert "stage1" in saved  # the flat hyper-parameters of before the typed configs
    plain, _ = load_trained_module(path)
    trained, _ = load_training_module(path)
    lightning = KeyframeModule.load_from_checkpoint(lightning_file(path, tmp_path), map_location="cpu")
    assert plain.config == trained.config == lightning.config
    assert dict(trained.hparams) == dict(lightning.hparams)
    assert plain.discovery == trained.hparams.discovery and plain.prices() == trained.reader().prices()
    assert lightning.hparams.optimizer["lr"] == saved["lr"] and trained.loss.beta_kl == saved["beta_kl"]
    expected = outputs(plain)
    for module in (trained, lightning):
        got = outputs(module.reader())
        assert got.keys() == expected.keys()
        for key, value in expected.items():
            torch.testing.assert_close(got[key], value, msg=key)


def test_a_typed_checkpoint_loads_back_with_no_other_argument(tmp_path):
    module = stage2("ours", offset_evidence=True, discovery="map", teacher_weight=2.0, delta_input="argmax")
    trainer = L.Trainer(logger=False, enable_checkpointing=False, enable_progress_bar=False, enable_model_summary=False)
    trainer.strategy.connect(module)
    trainer.save_checkpoint(tmp_path / "typed.ckpt")
    loaded = KeyframeModule.load_from_checkpoint(tmp_path / "typed.ckpt", weights_only=True)
    assert loaded.config == module.config and loaded.loss == module.loss and loaded.teacher == module.teacher
    assert loaded.hparams == module.hparams
    assert type(loaded.configure_optimizers()) is torch.optim.Adam
    for name, value in module.state_dict().items():
        assert torch.equal(value, loaded.state_dict()[name]), name


def test_the_stage_2_module_takes_typed_configs_in_at_most_twelve_arguments():
    arguments = list(inspect.signature(KeyframeModule.__init__).parameters)[1:]
    assert len(arguments) <= 12, f"KeyframeModule.__init__ takes {len(arguments)} arguments: {arguments}"
    assert arguments[:3] == ["net", "loss", "optimizer"]
    assert dataclasses.is_dataclass(KEYINConfig)
