"""keyin-train end to end at scale=smoke: both stages, checkpoints, resume, eval of the checkpoint."""

import json

import pytest
import torch

from keyin.lit.checkpoints import CONFIG_KEY, load_checkpoint
from tests.cli.runner import last_json, run


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    root = tmp_path_factory.mktemp("train")
    generated = run("generate", "splits={test: 8}", "progress=false", cwd=root)
    assert generated.returncode == 0, generated.stderr
    result = run("train", "experiment=brownian_keyin", "scale=smoke", "logger=none",
                 "trainer.enable_progress_bar=false", "hydra.run.dir=run", cwd=root)
    assert result.returncode == 0, result.stderr
    return root, last_json(result.stdout)


def test_training_writes_both_stages_and_scores_the_test_clips(trained):
    root, metrics = trained
    assert metrics["method"] == "keyin" and metrics["n_sequences"] == 8
    assert 0.0 <= metrics["f1"] <= 1.0
    assert json.loads((root / "run" / "metrics.json").read_text()) == metrics
    assert (root / "run" / "keyframes.png").is_file()
    for stage in ("interpolator", "keyframes"):
        checkpoint = load_checkpoint(root / "run" / "checkpoints" / stage / "last.ckpt", stage)
        assert checkpoint["global_step"] == 3
        assert checkpoint[CONFIG_KEY]["scale"]["stage1_steps"] == 3  # the full config travels


def test_frozen_stage1_weights_are_unchanged_by_stage2(trained):
    root, _ = trained
    stage1 = load_checkpoint(root / "run" / "checkpoints" / "interpolator" / "last.ckpt")["state_dict"]
    stage2 = load_checkpoint(root / "run" / "checkpoints" / "keyframes" / "last.ckpt")["state_dict"]
    frozen = [k for k in stage1 if k.split(".")[0] in ("encoder", "decoder", "interpolator")]
    assert frozen
    for key in frozen:
        torch.testing.assert_close(stage1[key], stage2[key], rtol=0, atol=0)


def test_eval_of_the_checkpoint_matches_the_training_run(trained):
    root, metrics = trained
    result = run("eval", "ckpt=run/checkpoints/keyframes/last.ckpt", "progress=false", cwd=root)
    assert result.returncode == 0, result.stderr
    evaluated = last_json(result.stdout)
    for key in ("f1", "precision", "recall", "f1_tol1", "n_sequences"):
        assert evaluated[key] == metrics[key]


def test_resume_continues_in_the_same_run_dir_without_redoing_steps(trained):
    root, metrics = trained
    result = run("train", "scale=smoke", "logger=none", "trainer.enable_progress_bar=false",
                 "resume=run", cwd=root)
    assert result.returncode == 0, result.stderr
    assert last_json(result.stdout)["f1"] == metrics["f1"]
    checkpoint = load_checkpoint(root / "run" / "checkpoints" / "keyframes" / "last.ckpt")
    assert checkpoint["global_step"] == 3


def test_stage2_without_a_stage1_checkpoint_names_the_fix(tmp_path):
    result = run("train", "scale=smoke", "stage=keyframes", "logger=none", cwd=tmp_path)
    assert result.returncode == 2
    assert "does not exist" in result.stderr and "Traceback" not in result.stderr


def test_a_checkpoint_of_the_wrong_stage_is_refused(trained, tmp_path):
    root, _ = trained
    result = run("train", "scale=smoke", "stage=keyframes", "logger=none",
                 f"interpolator_ckpt={root}/run/checkpoints/keyframes/last.ckpt", cwd=tmp_path)
    assert result.returncode == 2
    assert "is a 'keyframes' checkpoint but a 'interpolator' one is needed" in result.stderr


def test_eval_of_a_stage1_checkpoint_scores_its_best_segmentation(trained):
    root, _ = trained
    result = run("eval", "ckpt=run/checkpoints/interpolator/last.ckpt", "progress=false", cwd=root)
    assert result.returncode == 0, result.stderr
    metrics = last_json(result.stdout)
    assert metrics["method"] == "keyin_segmentation" and metrics["n_sequences"] == 8
    assert 0 < metrics["n_predicted"] <= 5  # at most M = 6 gaps, the last one closing the clip


def test_a_resumed_run_keeps_the_csv_metrics_of_the_first_process(tmp_path):
    common = ("scale=smoke", "stage=interpolator", "trainer.enable_progress_bar=false", "hydra.run.dir=run")
    assert run("train", *common, cwd=tmp_path).returncode == 0
    assert run("train", *common, "scale.stage1_steps=5", cwd=tmp_path).returncode == 0
    files = sorted((tmp_path / "run" / "csv").glob("version_*/metrics.csv"))
    assert len(files) == 2
    steps = [[int(line.split(",")[1]) for line in f.read_text().splitlines()[1:]] for f in files]
    assert max(steps[0]) < 3 <= max(steps[1])
