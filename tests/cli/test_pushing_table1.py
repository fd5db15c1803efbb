"""The pushing Table 1 sweep end to end at scale=smoke on a tiny generated pushing dataset."""

import json

import pytest
from hydra import compose, initialize_config_module

from keyin.cli import report
from keyin.cli.app import CONFIG_MODULE
from tests.cli.runner import run

TRAINED = ("keyin_plus", "jumpy", "static", "surprise")
SWEEP = ("-m", "experiment=pushing_table1", "scale=smoke", "logger=none", "num_workers=0", "trainer.enable_progress_bar=false",
         f"model={','.join(TRAINED)},constant", "seed=0")


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    root = tmp_path_factory.mktemp("pushing_table1")
    generated = run("generate", "dataset=pushing", "splits={train: 6, val: 4, test: 4}", "shard_size=4",
                    "progress=false", cwd=root)
    assert generated.returncode == 0, generated.stderr
    result = run("train", *SWEEP, "scale.batch_size=2", "scale.val_clips=2", cwd=root)
    assert result.returncode == 0, result.stderr
    return root / "runs" / "multirun" / "pushing_table1"


def test_every_pushing_model_trains_and_scores_its_keyframes(sweep, tmp_path, monkeypatch):
    for name in (*TRAINED, "constant"):
        metrics = json.loads((sweep / f"{name}_seed0" / "metrics.json").read_text())
        assert metrics["method"] == name and metrics["dataset"] == "pushing" and metrics["n_sequences"] == 4
        assert 0.0 <= metrics["f1"] <= 1.0
    assert (sweep / "stage1_ours_seed0" / "checkpoints" / "interpolator" / "last.ckpt").is_file()
    monkeypatch.chdir(tmp_path)  # the report finds each job's data where the job ran, not in its own cwd
    report.main([str(sweep), "--examples", "1"])
    table = (sweep / "report" / "table1.md").read_text()
    assert "| pushing | keyin_plus |" in table and "| 0.30 |" in table  # the paper's pushing column beside ours


def test_the_cpu_preset_takes_its_pushing_sizes_only_on_pushing():
    expected = {"conv_width": 8, "batch_size": 16, "stage1_steps": 2000}
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        pushing = compose("train", overrides=["scale=cpu", "experiment=pushing_table1"])
        brownian = compose("train", overrides=["scale=cpu", "dataset=brownian"])
    assert {key: pushing.scale[key] for key in expected} == expected
    assert all(brownian.scale[key] != value for key, value in expected.items())


@pytest.mark.parametrize(("backbone", "dataset", "offsets"), [
    ("paper", "pushing", (2, 6)), ("paper", "brownian", (2, 8)), ("ours", "pushing", (1, 6)), ("ours", "brownian", (1, 10)),
])
def test_the_backbone_takes_the_stage1_segment_lengths_of_its_dataset(backbone, dataset, offsets):
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        interpolator = compose("train", overrides=[f"backbone={backbone}", f"dataset={dataset}"]).model.interpolator
    assert (interpolator.offset_min, interpolator.offset_max) == offsets
