"""keyin-train model=tap end to end at scale=smoke on a few pushing demos: checkpoint, metrics.json,
the subgoal picture, and a finished run that a resumable sweep skips."""

import json

import imageio.v3 as iio
import pytest
import torch

from keyin.lit.registry import load_trained_module
from keyin.lit.tap import TAPModule
from tests.cli.runner import last_json, run, train_on_few_pushing_demos

TRAIN = ("model=tap", "dataset=pushing", "scale=smoke", "logger=none", "num_workers=0",
         "trainer.enable_progress_bar=false", "hydra.run.dir=run")


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    root = tmp_path_factory.mktemp("tap")
    return root, train_on_few_pushing_demos(root, *TRAIN)


def test_training_writes_tap_metrics_and_its_subgoal_grid(trained):
    root, metrics = trained
    assert metrics["method"] == "tap" and metrics["dataset"] == "pushing" and metrics["n_sequences"] == 4
    assert 0 < metrics["bce_per_pixel"] < 10 and 0 < metrics["argmin_relative"] < 1 and 0 <= metrics["argmin_last"] <= 1
    assert json.loads((root / "run" / "metrics.json").read_text()) == metrics
    grid = iio.imread(root / "run" / "tap_grid.png")
    assert grid.shape == (4 * 68, 3 * 68, 3)  # (start, prediction, goal) of each test clip, 2-pixel borders


def test_the_checkpoint_loads_as_a_subgoal_predictor(trained):
    root, _ = trained
    module, config = load_trained_module(root / "run" / "checkpoints" / "tap" / "last.ckpt", stage="tap")
    assert isinstance(module, TAPModule) and config["model"]["name"] == "tap"
    images = module.subgoal(torch.rand(2, 3, 64, 64), torch.rand(2, 3, 64, 64))
    assert images.shape == (2, 3, 64, 64) and ((images >= 0) & (images <= 1)).all()


def test_a_finished_run_is_skipped_by_a_resumable_sweep(trained):
    root, metrics = trained
    result = run("train", *TRAIN, "skip_finished=true", cwd=root)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "finished earlier; skipped" in result.stdout and last_json(result.stdout) == metrics
