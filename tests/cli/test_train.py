"""keyin-train end to end at scale=smoke: both stages, checkpoints, resume, eval of the checkpoint."""

import json
import shutil
from pathlib import Path

import imageio.v3 as iio
import pytest
import torch

from keyin.lit import checkpoints
from keyin import __version__
from keyin.lit.checkpoints import CONFIG_KEY, VERSION_KEY, load_checkpoint
from keyin.lit.registry import load_trained_module
from keyin.lit.interpolator import InterpolatorModule
from tests.cli.runner import error_line, last_json, run
from tests.configs import OLD_SMOKE_KEYIN, OLD_SMOKE_TWO_STAGES
from tests.faults import fill_disk_on


# keyin 0.1's `keyin-train experiment=brownian_keyin scale=smoke`, in today's names.
KEYIN_SMOKE = ("experiment=brownian_keyin", "scale=smoke", *OLD_SMOKE_KEYIN, "logger=none", "num_workers=0",
               "trainer.enable_progress_bar=false")
REFERENCE = json.loads((Path(__file__).parents[1] / "reference" / "smoke_keyin_metrics.json").read_text())


@pytest.fixture(scope="module")
def trained(tmp_path_factory):
    root = tmp_path_factory.mktemp("train")
    generated = run("generate", "splits={test: 8}", "progress=false", cwd=root)
    assert generated.returncode == 0, generated.stderr
    result = run("train", *KEYIN_SMOKE, "hydra.run.dir=run", cwd=root)
    assert result.returncode == 0, result.stderr
    return root, last_json(result.stdout)


def test_training_writes_both_stages_and_scores_the_test_clips(trained):
    root, metrics = trained
    assert metrics["method"] == "keyin_plus" and metrics["n_sequences"] == 8
    assert 0.0 <= metrics["f1"] <= 1.0
    assert json.loads((root / "run" / "metrics.json").read_text()) == metrics
    assert (root / "run" / "keyframes.png").is_file()
    for stage in ("interpolator", "keyframes"):
        checkpoint = load_checkpoint(root / "run" / "checkpoints" / stage / "last.ckpt", stage)
        assert checkpoint["global_step"] == 3
        assert checkpoint[CONFIG_KEY]["scale"]["stage1_steps"] == 3  # the full config travels
        assert checkpoint[VERSION_KEY] == __version__


def test_the_restructured_configs_train_what_keyin_0_1_trained(trained):
    """The same seed and the same modules give keyin 0.1's smoke metrics (recorded before the
    restructure; today's metrics add the information rule's columns beside them)."""
    _, metrics = trained
    old = REFERENCE["metrics"]
    assert {key: metrics[key] for key in old if key not in ("method", "variants")} == {
        key: value for key, value in old.items() if key not in ("method", "variants")}
    for name, scores in old["variants"].items():
        today = metrics["variants"][name.replace("keyin", "keyin_plus", 1)]
        assert {key: today[key] for key in scores} == scores


def test_frozen_stage1_weights_are_unchanged_by_stage2(trained):
    root, _ = trained
    stage1 = load_checkpoint(root / "run" / "checkpoints" / "interpolator" / "last.ckpt")["state_dict"]
    stage2 = load_checkpoint(root / "run" / "checkpoints" / "keyframes" / "last.ckpt")["state_dict"]
    frozen = [k for k in stage1 if k.split(".")[0] in ("encoder", "decoder", "interpolator")]
    assert frozen
    for key in frozen:
        torch.testing.assert_close(stage1[key], stage2[f"model.{key}"], rtol=0, atol=0)


def test_eval_of_the_checkpoint_matches_the_training_run(trained):
    root, metrics = trained
    result = run("eval", "ckpt=run/checkpoints/keyframes/last.ckpt", "progress=false", cwd=root)
    assert result.returncode == 0, result.stderr
    evaluated = last_json(result.stdout)
    for key in ("f1", "precision", "recall", "f1_tol1", "n_sequences"):
        assert evaluated[key] == metrics[key]


def test_eval_scores_the_chosen_rules_on_the_first_clips(trained):
    root, metrics = trained
    result = run("eval", "ckpt=run/checkpoints/keyframes/last.ckpt", "discovery=[map]", "clips=3", "progress=false",
                 "hydra.run.dir=eval_map", cwd=root)
    assert result.returncode == 0, result.stderr
    evaluated = last_json(result.stdout)
    assert evaluated["method"] == "keyin_plus_map" and evaluated["n_sequences"] == 3 and "variants" not in evaluated
    assert len((root / "eval_map" / "per_video.csv").read_text().splitlines()) == 1 + 3  # generated clips: one video each
    bad = run("eval", "ckpt=run/checkpoints/keyframes/last.ckpt", "discovery=viterbi", "progress=false", cwd=root)
    assert error_line(bad) == (
        "error: discovery=viterbi: this model discovers by ['offsets', 'boundaries', 'map', 'map_pruned', 'segmentation'], not ['viterbi']; pick among those")


def test_resume_continues_in_the_same_run_dir_without_redoing_steps(trained):
    """A finished stage is loaded, not fitted again: same scores, the same training time (its stages' own, kept in
    their checkpoints), and its file keeps its bytes (its hash)."""
    root, metrics = trained
    files = {stage: root / "run" / "checkpoints" / stage / "last.ckpt" for stage in ("interpolator", "keyframes")}
    before = {stage: path.read_bytes() for stage, path in files.items()}
    result = run("train", *KEYIN_SMOKE, "resume=run", cwd=root)
    assert result.returncode == 0, result.stderr
    resumed = last_json(result.stdout)
    assert resumed["f1"] == metrics["f1"] and resumed["train_seconds"] == metrics["train_seconds"] > 0
    assert {stage: path.read_bytes() for stage, path in files.items()} == before
    assert load_checkpoint(files["keyframes"])["global_step"] == 3


def test_the_same_seed_trains_the_same_weights_and_metrics_twice(trained):
    root, metrics = trained
    result = run("train", *KEYIN_SMOKE, "hydra.run.dir=again", cwd=root)
    assert result.returncode == 0, result.stderr
    again = last_json(result.stdout)
    varying = {"run_dir", "train_seconds", "score_seconds"}  # where it ran, and how long it took
    assert {k: v for k, v in again.items() if k not in varying} == {k: v for k, v in metrics.items() if k not in varying}
    assert again["train_seconds"] > 0 and again["score_seconds"] > 0
    for stage in ("interpolator", "keyframes"):
        first = load_checkpoint(root / "run" / "checkpoints" / stage / "last.ckpt")["state_dict"]
        second = load_checkpoint(root / "again" / "checkpoints" / stage / "last.ckpt")["state_dict"]
        assert first.keys() == second.keys()
        for key in first:
            torch.testing.assert_close(first[key], second[key], rtol=0, atol=0)


def test_stage2_without_a_stage1_checkpoint_names_the_fix(tmp_path):
    result = run("train", "scale=smoke", "stage=keyframes", "logger=none", cwd=tmp_path)
    assert result.returncode == 2
    assert "does not exist" in result.stderr and "Traceback" not in result.stderr
    assert "train stage 1 first (stage=both or stage=interpolator) or pass interpolator_ckpt=" in result.stderr


def test_the_papers_open_choices_train_on_the_stage_1_inside_a_stage_2_checkpoint(trained, tmp_path):
    """Issue 43's options compose, train at scale=smoke on the stage 1 taken from a stage-2
    checkpoint (whose weights stay as they were), and load back from their checkpoint."""
    root, _ = trained
    source = root / "run" / "checkpoints" / "keyframes" / "last.ckpt"
    result = run("train", "scale=smoke", "backbone=ours", "model=keyin_paper", "stage=keyframes", "logger=none",
                 "trainer.enable_progress_bar=false", f"interpolator_ckpt={source}", "hydra.run.dir=run",
                 "model.keyframes.delta_input=straight_through", "model.keyframes.loss_reduction=per_pixel",
                 "model.keyframes.entropy_bonus=0.5", "model.keyframes.entropy_bonus_steps=2", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    trained_path = tmp_path / "run" / "checkpoints" / "keyframes" / "last.ckpt"
    module, config = load_trained_module(trained_path)
    assert config["model"]["name"] == "keyin_paper" and module.model.delta_input == "straight_through"
    loss = load_checkpoint(trained_path)["hyper_parameters"]["loss"]
    assert loss["reduction"] == "per_pixel" and loss["entropy_bonus"] == 0.5
    given = load_checkpoint(source)["state_dict"]
    for name, value in module.model.interpolator.state_dict().items():
        torch.testing.assert_close(value, given[f"model.interpolator.{name}"])


def test_a_checkpoint_of_the_wrong_stage_is_refused(trained, tmp_path):
    root, _ = trained
    checkpoint = torch.load(root / "run" / "checkpoints" / "keyframes" / "last.ckpt", weights_only=True)
    torch.save(dict(checkpoint, keyin_stage="surprise"), tmp_path / "surprise.ckpt")
    result = run("train", "scale=smoke", "stage=keyframes", "logger=none",
                 f"interpolator_ckpt={tmp_path}/surprise.ckpt", cwd=tmp_path)
    assert result.returncode == 2
    assert "surprise.ckpt is a 'surprise' checkpoint; stage 2 starts from the stage-1 checkpoint" in result.stderr
    assert "or from the stage 1 inside a stage-2 checkpoint" in result.stderr


def test_eval_of_a_stage1_checkpoint_scores_its_best_segmentation(trained):
    root, _ = trained
    result = run("eval", "ckpt=run/checkpoints/interpolator/last.ckpt", "progress=false", cwd=root)
    assert result.returncode == 0, result.stderr
    metrics = last_json(result.stdout)
    assert metrics["method"] == "keyin_plus_segmentation" and metrics["n_sequences"] == 8
    assert 0 < metrics["n_predicted"] <= 5  # at most M = 6 gaps, the last one closing the clip


VIDEO_KEYS = {"psnr_best_of_k", "ssim_best_of_k", "psnr_mean", "ssim_mean", "psnr_posterior", "ssim_posterior",
              "psnr_blank", "ssim_blank", "k"}


def test_eval_with_video_samples_adds_video_metrics_and_rollouts(trained):
    root, metrics = trained
    result = run("eval", "ckpt=run/checkpoints/keyframes/last.ckpt", "video_samples=2", "progress=false",
                 "hydra.run.dir=video", cwd=root)
    assert result.returncode == 0, result.stderr
    evaluated = last_json(result.stdout)
    assert evaluated["f1"] == metrics["f1"]
    video = evaluated["video"]
    assert set(video) == VIDEO_KEYS and video["k"] == 2
    assert video["psnr_best_of_k"] >= video["psnr_mean"] and video["ssim_best_of_k"] >= video["ssim_mean"]
    assert 0 < video["psnr_mean"] < 100 and -1 <= video["ssim_mean"] <= 1
    assert json.loads((root / "video" / "metrics.json").read_text()) == evaluated
    rollouts = iio.imread(root / "video" / "rollouts.png")
    assert rollouts.shape[:2] == (3 * 4 * 36, 35 * 36)  # 4 clips x (truth, posterior, sample), 5 + 30 frames
    assert (root / "video" / "rollouts.gif").is_file()
    pictured = evaluated["video_pictured"]  # samples.png: the truth, then each of the k samples, of 4 clips
    assert [len(clip["samples"]) for clip in pictured["clips"]] == [2] * 4 and pictured["k"] == 2
    assert iio.imread(root / "video" / "samples.png").ndim == 3
    assert iio.imread(root / "video" / "samples.gif", index=None).shape[0] == 35


def test_video_samples_of_a_stage1_checkpoint_give_one_error_line(trained):
    root, _ = trained
    result = run("eval", "ckpt=run/checkpoints/interpolator/last.ckpt", "video_samples=2", "progress=false", cwd=root)
    assert "but ckpt= holds a 'interpolator' checkpoint; drop video_samples=" in error_line(result)


def test_a_resumed_run_keeps_the_csv_metrics_of_the_first_process(tmp_path):
    common = ("scale=smoke", "stage=interpolator", "trainer.enable_progress_bar=false", "hydra.run.dir=run")
    assert run("train", *common, cwd=tmp_path).returncode == 0
    assert run("train", *common, "scale.stage1_steps=5", cwd=tmp_path).returncode == 0
    files = sorted((tmp_path / "run" / "csv").glob("version_*/metrics.csv"))
    assert len(files) == 2
    steps = [[int(line.split(",")[1]) for line in f.read_text().splitlines()[1:]] for f in files]
    assert max(steps[0]) < 3 <= max(steps[1])


STAGE1 = ("scale=smoke", "stage=interpolator", "logger=none", "num_workers=0",
          "trainer.enable_progress_bar=false", "hydra.run.dir=run")


def stage1_checkpoint(root):
    return root / "run" / "checkpoints" / "interpolator" / "last.ckpt"


def test_resuming_a_run_dir_with_other_model_sizes_is_refused(tmp_path):
    assert run("train", *STAGE1, cwd=tmp_path).returncode == 0
    before = stage1_checkpoint(tmp_path).read_bytes()
    line = error_line(run("train", *STAGE1, "scale.embed_dim=32", cwd=tmp_path))
    assert "holds a model of other sizes (embed_dim=16 (now 32))" in line
    assert "resume with the overrides it was trained with, or start a new run dir" in line
    assert stage1_checkpoint(tmp_path).read_bytes() == before


def test_resuming_stage2_as_another_model_is_refused(trained, tmp_path):
    root, _ = trained
    shutil.copytree(root / "run" / "checkpoints", tmp_path / "run" / "checkpoints")
    line = error_line(run("train", "scale=smoke", "model=jumpy", *OLD_SMOKE_TWO_STAGES, "logger=none", "resume=run",
                          cwd=tmp_path))
    assert "holds a model=keyin_plus checkpoint but this run trains model=jumpy" in line
    assert "resume it with model=keyin_plus, or train model=jumpy in a new run dir" in line


def test_a_non_finite_loss_stops_with_one_error_and_keeps_the_last_good_checkpoint(tmp_path, monkeypatch):
    original = InterpolatorModule.training_step

    def poisoned(self, batch, batch_idx):  # NaN from the third step on
        loss = original(self, batch, batch_idx)
        return loss * float("nan") if self.global_step >= 2 else loss

    monkeypatch.setattr(InterpolatorModule, "training_step", poisoned)
    line = error_line(run("train", *STAGE1, "scale.stage1_steps=6", cwd=tmp_path))
    assert "non-finite loss nan at step 3" in line
    assert f"the last good checkpoint is {stage1_checkpoint(tmp_path)}" in line
    assert "lower the learning rate (scale.lr_stage1=...) and run the same command again" in line
    checkpoint = load_checkpoint(stage1_checkpoint(tmp_path))
    assert checkpoint["global_step"] == 2
    assert all(torch.isfinite(value).all() for value in checkpoint["state_dict"].values())


def test_a_full_disk_at_a_checkpoint_keeps_the_previous_one(tmp_path, monkeypatch):
    writes = []  # the disk fills at the second last.ckpt (best.ckpt is written at each better validation)
    fill_disk_on(monkeypatch, checkpoints, lambda path: path.name == "last.ckpt" and (writes.append(path) or len(writes) == 2))
    line = error_line(run("train", *STAGE1, "scale.stage1_steps=6", cwd=tmp_path))
    assert f"No space left on device ({stage1_checkpoint(tmp_path)})" in line
    assert "free disk space" in line and "run the same command again" in line
    assert load_checkpoint(stage1_checkpoint(tmp_path))["global_step"] == 2
    assert sorted(p.name for p in stage1_checkpoint(tmp_path).parent.iterdir()) == ["best.ckpt", "last.ckpt"]


@pytest.mark.slow  # torch.compile of every network: minutes of compilation on 2 CPU cores
def test_compiled_networks_train_and_keep_the_checkpoint_names(tmp_path):
    assert run("generate", "splits={test: 4}", "progress=false", cwd=tmp_path).returncode == 0
    runs = {}
    for name, compiled in (("plain", "false"), ("compiled", "true")):
        result = run("train", "model=surprise", "scale=smoke", "logger=none", f"compile={compiled}",
                     "trainer.enable_progress_bar=false", f"hydra.run.dir={name}", cwd=tmp_path)
        assert result.returncode == 0, result.stderr[-3000:]
        runs[name] = load_checkpoint(tmp_path / name / "checkpoints" / "surprise" / "last.ckpt")["state_dict"]
    assert runs["plain"].keys() == runs["compiled"].keys()


def test_a_warm_start_begins_at_every_weight_of_init_ckpt(trained, tmp_path):
    """init_ckpt=: stage 2 starts from the checkpoint's weights (predictor and stage 1), trains on from
    there, and another model's checkpoint is refused with the fix."""
    root, _ = trained
    source = root / "run" / "checkpoints" / "keyframes" / "last.ckpt"
    result = run("train", *KEYIN_SMOKE, "stage=keyframes", f"init_ckpt={source}", "scale.stage2_steps=1",
                 "scale.val_every=1", "evaluate=false", "hydra.run.dir=warm", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    given = load_checkpoint(source)["state_dict"]
    trained_on = load_checkpoint(tmp_path / "warm" / "checkpoints" / "keyframes" / "last.ckpt")["state_dict"]
    assert given.keys() == trained_on.keys()
    frozen = [name for name in given if name.startswith(("model.encoder.", "model.decoder.", "model.interpolator."))]
    for name in frozen:  # stage 1 stays frozen: exactly the warm start's
        torch.testing.assert_close(trained_on[name], given[name], rtol=0, atol=0)
    moved = [name for name in given if name not in frozen and not torch.equal(trained_on[name], given[name])]
    assert moved and all(name.startswith("model.predictor.") for name in moved)  # one Adam step from there
    assert max((trained_on[name] - given[name]).abs().max().item() for name in moved) < 0.05

    refused = run("train", "scale=smoke", "model=keyin", "stage=keyframes", f"init_ckpt={source}", "logger=none",
                  "hydra.run.dir=other", cwd=tmp_path)
    assert refused.returncode == 2 and "Traceback" not in refused.stderr
    assert "whose parameter shapes differ from this run's; warm-start with the model= and scale=" in error_line(refused)
