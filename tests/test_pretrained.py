"""Pretrained models: a slimmed checkpoint loads by name, gives the same discoveries as the full
one up to half precision, refuses a changed file; every shipped model is the file its card names."""

import json

import numpy as np

import pytest
import torch

import keyin.pretrained as pretrained
from keyin.data.clips import ShardClips
from keyin.data.hdf5 import split_files
from keyin.errors import CheckpointError
from keyin.io import sha256_of
from keyin.lit.checkpoints import load_checkpoint
from keyin.lit.registry import load_trained_module
from tests.cli.runner import error_line, run
from tests.configs import OLD_SMOKE_KEYIN


@pytest.fixture(scope="module")
def smoke_checkpoint(tmp_path_factory):
    root = tmp_path_factory.mktemp("pretrained")
    assert run("generate", "splits={test: 4}", "progress=false", cwd=root).returncode == 0
    result = run("train", "experiment=brownian_keyin", "scale=smoke", *OLD_SMOKE_KEYIN, "logger=none",
                 "trainer.enable_progress_bar=false", "evaluate=false", "num_workers=0", "hydra.run.dir=run", cwd=root)
    assert result.returncode == 0, result.stderr
    return root, root / "run" / "checkpoints" / "keyframes" / "last.ckpt"


@pytest.fixture
def shipped(smoke_checkpoint, tmp_path, monkeypatch):
    """The smoke checkpoint exported as pretrained:smoke into a folder of its own."""
    _, path = smoke_checkpoint
    monkeypatch.setattr(pretrained, "FOLDER", tmp_path)
    monkeypatch.setattr(pretrained.resolve, "__defaults__", (tmp_path,))
    file = pretrained.export(load_checkpoint(path), "smoke", {"command": "test"}, tmp_path)
    return path, file


def test_a_slimmed_checkpoint_keeps_the_weights_to_half_precision_and_drops_the_optimizer(shipped):
    path, file = shipped
    full, slim = load_checkpoint(path), load_checkpoint("pretrained:smoke")
    assert "optimizer_states" in full and "optimizer_states" not in slim
    assert file.stat().st_size < path.stat().st_size / 2
    for name, value in full["state_dict"].items():
        assert slim["state_dict"][name].dtype == value.dtype
        torch.testing.assert_close(slim["state_dict"][name], value, rtol=1e-3, atol=1e-4)
    card = json.loads((file.parent / "models.json").read_text())["smoke"]
    assert card["sha256"] == sha256_of(file) and card["command"] == "test"


def test_the_pretrained_module_finds_the_same_keyframes_as_the_full_one(smoke_checkpoint, shipped):
    root, _ = smoke_checkpoint
    path, _ = shipped
    clips = ShardClips(split_files(root / "data" / "brownian", "test"), (32, 32, 1), 5, 30)
    frames, lengths = torch.stack([clip["frames"] for clip in clips]), torch.stack([clip["future_length"] for clip in clips])
    found = {}
    for source in (path, "pretrained:smoke"):
        module, config = load_trained_module(source)
        found[str(source)] = {name: find(frames, lengths) for name, find in module.discoverers(config["model"]["name"]).items()}
    assert found[str(path)] == found["pretrained:smoke"]


def test_an_unknown_name_or_a_changed_file_is_refused(shipped):
    _, file = shipped
    with pytest.raises(CheckpointError, match="no pretrained model named 'pushing'; this keyin ships pretrained:smoke"):
        load_checkpoint("pretrained:pushing")
    file.write_bytes(file.read_bytes() + b"0")
    with pytest.raises(CheckpointError, match="not the file keyin shipped"):
        load_checkpoint("pretrained:smoke")


def test_keyin_eval_names_the_unknown_pretrained_model(smoke_checkpoint):
    root, _ = smoke_checkpoint
    result = run("eval", "ckpt=pretrained:nothing", "progress=false", cwd=root)
    assert error_line(result).startswith("error: no pretrained model named 'nothing'; this keyin ships")


@pytest.mark.parametrize("name", sorted(pretrained.registry()))
def test_every_shipped_model_is_the_file_its_card_names(name):
    checkpoint = load_checkpoint(f"{pretrained.PREFIX}{name}")
    card = pretrained.registry()[name]
    assert checkpoint["keyin_config"]["model"]["name"] == card["model"]
    assert checkpoint["keyin_config"]["dataset"]["name"] == card["dataset"]


def test_the_bundled_example_video_is_the_generators_clip_and_its_labels_its_turns():
    from keyin.data.brownian import BrownianGenerator
    from keyin.data.sources import decoded_frames
    from keyin.cli.pretrained import EXAMPLE, EXAMPLE_LABELS

    arrays, _ = BrownianGenerator(n_cond=1, n_future=199).generate(0, seed=777)
    decoded = np.stack(list(decoded_frames(pretrained.FOLDER / EXAMPLE)))
    assert (decoded.max(axis=-1) == arrays["frames"][..., 0]).all()
    labels = json.loads((pretrained.FOLDER / EXAMPLE_LABELS).read_text())
    assert labels == {EXAMPLE: arrays["keyframes"].nonzero()[0].tolist()}


def test_export_slims_run_checkpoints_into_a_folder_named_and_described_by_their_runs(smoke_checkpoint, tmp_path, monkeypatch, capsys):
    from keyin.cli.pretrained import main

    _, path = smoke_checkpoint
    monkeypatch.setattr("sys.argv", ["keyin.cli.pretrained", "export", str(path), "--folder", str(tmp_path / "models")])
    main()
    file = tmp_path / "models" / "run.ckpt"  # the run dir's name
    assert capsys.readouterr().out.strip() == str(file)
    card = json.loads((tmp_path / "models" / "models.json").read_text())["run"]
    assert card["command"].startswith("keyin-train experiment=brownian_keyin scale=smoke ")  # its .hydra/hydra.yaml
    assert card["source_sha256"] == sha256_of(path) and card["sha256"] == sha256_of(file)
    full, slim = load_checkpoint(path), load_checkpoint(file)  # a plain path loads as any checkpoint
    assert slim["state_dict"].keys() == full["state_dict"].keys() and "optimizer_states" not in slim
    monkeypatch.setattr("sys.argv", ["keyin.cli.pretrained", "export", str(path), str(path), "--name", "x"])
    with pytest.raises(SystemExit, match="--name and --command name one checkpoint"):
        main()


def val_metrics(tmp_path, ckpt="pretrained:smoke", split="val", own=0.50, map_f1=0.505, boundaries=0.40):
    """A keyin-eval metrics.json of the smoke model (its own rule `offsets`, named keyin_plus) on 4 clips."""
    metrics = {"ckpt": ckpt, "split": split, "method": "keyin_plus", "f1_interior": own, "n_sequences": 4,
               "variants": {"keyin_plus_map": {"f1_interior": map_f1}, "keyin_plus_boundaries": {"f1_interior": boundaries}}}
    path = tmp_path / f"metrics_{split}.json"
    path.write_text(json.dumps(metrics))
    return path


def test_rules_records_the_cheapest_rule_within_0_01_of_map_and_keyin_discover_uses_it(shipped, tmp_path, monkeypatch, capsys):
    from omegaconf import OmegaConf

    from keyin.cli.discover import chosen_rule
    from keyin.cli.pretrained import main

    monkeypatch.setattr(pretrained.recorded_rule, "__defaults__", (tmp_path,))
    monkeypatch.setattr("sys.argv", ["keyin.cli.pretrained", "rules", "smoke", str(val_metrics(tmp_path)), "--folder", str(tmp_path)])
    main()
    recorded = pretrained.registry(tmp_path)["smoke"]["default_rule"]
    assert recorded == {"rule": "offsets", "val_f1_interior": {"boundaries": 0.4, "map": 0.505, "offsets": 0.5},
                        "val_clips": 4, "tolerance": 0.01, "metrics": str(tmp_path / "metrics_val.json")}
    assert "default rule is offsets" in capsys.readouterr().out
    module, _ = load_trained_module("pretrained:smoke")
    auto = OmegaConf.create({"rule": "auto", "ckpt": "pretrained:smoke"})
    assert chosen_rule(auto, module) == "offsets"
    assert "recorded default" in capsys.readouterr().err
    assert chosen_rule(OmegaConf.create({"rule": "auto", "ckpt": str(shipped[0])}), module) == "map"  # not shipped: map
    assert chosen_rule(OmegaConf.create({"rule": "boundaries", "ckpt": "pretrained:smoke"}), module) == "boundaries"


def test_rules_refuses_scores_of_the_test_split(shipped, tmp_path, monkeypatch):
    from keyin.cli.pretrained import main

    monkeypatch.setattr("sys.argv", ["keyin.cli.pretrained", "rules", "smoke", str(val_metrics(tmp_path, split="test")),
                                     "--folder", str(tmp_path)])
    with pytest.raises(SystemExit, match="scored ckpt=pretrained:smoke on split=test; record the rule from"):
        main()


# keyin-discover's keyframes of the bundled example video by each shipped model at rule=auto (its recorded
# default rule), as they were before the rules became objects (issue 59; 2026-12-06, float32 on the CPU).
EXAMPLE_KEYFRAMES = {
    "brownian": ("map_pruned", [6, 12, 19, 26, 33, 39, 45, 51, 59, 67, 73, 79, 85, 93, 101, 109, 115, 123, 130, 137, 145,
                                151, 157, 165, 174, 179, 186, 194]),
    "pushing": ("boundaries", [6, 11, 17, 23, 27, 33, 39, 45, 51, 53, 59, 65, 70, 74, 79, 84, 90, 96, 101, 107, 112, 118,
                               124, 130, 134, 138, 147, 152, 157, 162, 167, 171, 174, 179, 184, 190, 196]),
    "metaworld": ("map", [1, 11, 24, 26, 31, 35, 47, 55, 59, 70, 76, 81, 86, 97, 108, 111, 118, 121, 127, 133, 142, 144,
                          153, 161, 172, 181, 188, 192]),
}


@pytest.mark.parametrize("name", sorted(EXAMPLE_KEYFRAMES))
def test_each_shipped_model_finds_its_recorded_keyframes_of_the_example_video(name, tmp_path):
    from keyin.cli.pretrained import EXAMPLE

    result = run("discover", f"ckpt={pretrained.PREFIX}{name}", f"input={pretrained.FOLDER / EXAMPLE}", "rule=auto",
                 "pictures=false", "progress=false", "device=cpu", "hydra.run.dir=out", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    record = json.loads((tmp_path / "out" / EXAMPLE / "keyframes.json").read_text())
    assert (record["model"]["rule"], [keyframe["frame"] for keyframe in record["keyframes"]]) == EXAMPLE_KEYFRAMES[name]
