"""The researcher's loop end to end at scale=smoke: a sweep over methods in one folder, its report,
TensorBoard runs named by what they change with the whole config and the results, best and last
checkpoints per stage, and an Optuna search (hydra/sweeper=tune)."""

import json

import pytest
import yaml

from keyin.cli import report
from keyin.lit.checkpoints import load_checkpoint, run_checkpoint
from tests.cli.runner import last_json, run

event_accumulator = pytest.importorskip("tensorboard.backend.event_processing.event_accumulator")
from tensorboard.plugins.hparams import plugin_data_pb2  # noqa: E402

METHODS = {"keyin": "keyin_paper", "keyin_plus": "keyin_plus", "jumpy": "jumpy", "static": "static", "surprise": "surprise"}
QUIET = ("num_workers=0", "trainer.enable_progress_bar=false")


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    """``keyin-train -m model=keyin,keyin_plus,jumpy,static,surprise scale=smoke logger=tensorboard`` on 4 test clips."""
    root = tmp_path_factory.mktemp("sweep")
    assert run("generate", "splits={test: 4}", "progress=false", cwd=root).returncode == 0
    result = run("train", "-m", f"model={','.join(METHODS)}", "scale=smoke", "logger=tensorboard", *QUIET, cwd=root)
    assert result.returncode == 0, result.stderr[-3000:]
    (folder,) = (root / "runs" / "multirun" / "train").iterdir()  # one sweep folder, whatever is swept
    return root, folder


def tensorboard_run(path):
    """A TensorBoard run's scalar tags, its hyperparameters and its HParams metrics, read by TensorBoard."""
    events = event_accumulator.EventAccumulator(str(path))
    events.Reload()
    params, metrics = {}, []
    for content in events.PluginTagToContent("hparams").values():
        data = plugin_data_pb2.HParamsPluginData.FromString(content)
        if data.HasField("session_start_info"):
            params = {key: value.WhichOneof("kind") and getattr(value, value.WhichOneof("kind"))
                      for key, value in data.session_start_info.hparams.items()}
        if data.HasField("experiment"):
            metrics = [info.name.tag for info in data.experiment.metric_infos]
    scalars = {tag: [event.value for event in events.Scalars(tag)] for tag in events.Tags()["scalars"]}
    return scalars, params, metrics


def test_a_sweep_over_methods_is_one_folder_and_one_report(sweep, capsys):
    root, folder = sweep
    jobs = {f"model={model},num_workers=0,scale=smoke" for model in METHODS}  # named by their overrides
    assert {path.name for path in folder.iterdir() if (path / "metrics.json").is_file()} == jobs
    assert (folder / "multirun.yaml").is_file()
    report.main([str(folder), "--brief"])
    rows = [line.split(" | ")[1] for line in capsys.readouterr().out.splitlines()[2:]]
    # a row per method (and the variants it scores beside it); the paper's KEYIN at smoke sizes says so in its name
    methods = {name if name != "keyin_paper" else "keyin_paper · scale=smoke" for name in METHODS.values()}
    assert methods <= set(rows)
    assert len([row for row in rows if row in methods]) == 5


def test_every_run_is_named_by_what_it_changes_and_holds_its_config_and_results(sweep):
    _, folder = sweep
    runs = sorted((folder / "tensorboard").iterdir())
    assert [path.name for path in runs] == sorted(
        f"{method}-brownian-seed0[model={model},num_workers=0,scale=smoke]" for model, method in METHODS.items())
    for path in runs:
        scalars, params, metrics = tensorboard_run(path)
        method = path.name.split("-")[0]
        assert {"Method": method, "Dataset": "brownian", "Seed": 0, "Scale": "smoke"}.items() <= params.items()
        assert params["model/name"] == method and params["scale/stage2_steps"] == 3  # the whole config, flattened
        assert {"test/f1", "test/f1_interior", "test/f1_tol1_interior", "val/f1_best", "val/f1_best_step"} <= set(metrics)
        assert "hp_metric" not in scalars
        job = json.loads((folder / f"model={next(m for m, n in METHODS.items() if n == method)},num_workers=0,scale=smoke"
                          / "metrics.json").read_text())
        assert scalars["test/f1"] == [pytest.approx(job["f1"])]
        assert scalars["val/f1_best"] == [pytest.approx(job["val_f1_best"])]
        assert len(scalars["train/loss"]) == 3  # every step of the 3 at scale=smoke reaches the logger
        if method != "surprise":  # two stages: stage 1 in its own namespace, each stage's steps its own
            assert len(scalars["stage1/train/loss"]) == 3 and "stage1/val/bce_per_frame" in scalars


def test_each_stage_keeps_its_best_and_last_checkpoint_and_metrics_name_the_best_step(sweep):
    root, folder = sweep
    job = folder / "model=keyin_plus,num_workers=0,scale=smoke"
    metrics = json.loads((job / "metrics.json").read_text())
    for stage, monitor in (("interpolator", "val/bce_per_frame"), ("keyframes", "val/f1")):
        assert sorted(p.name for p in (job / "checkpoints" / stage).iterdir()) == ["best.ckpt", "last.ckpt"]
        best = load_checkpoint(job / "checkpoints" / stage / "best.ckpt", stage)
        assert best["global_step"] == 2 and metrics["best"][stage]["step"] == 2  # validated at step 2 of 3
        assert metrics["best"][stage]["monitor"] == monitor
        last = load_checkpoint(job / "checkpoints" / stage / "last.ckpt")
        assert last["global_step"] == 3
        choices = last["keyin_config"]["choices"]  # each sweep job's own config-group choices travel with its model
        assert (choices["model"], choices["scale"], choices["backbone"]) == ("keyin_plus", "smoke", "ours")
    assert (metrics["val_f1_best"], metrics["val_f1_best_step"]) == (metrics["best"]["keyframes"]["value"], 2)
    assert run_checkpoint(job / "best") == job / "checkpoints" / "keyframes" / "best.ckpt"  # keyin-eval, keyin-discover
    assert run_checkpoint(job / "last") == job / "checkpoints" / "keyframes" / "last.ckpt"
    # a job folder's name holds '=' and ',': quoted, as Hydra reads any such value
    evaluated = run("eval", f"ckpt='{job}/best'", "progress=false", "hydra.run.dir=eval_best", cwd=root)
    assert evaluated.returncode == 0, evaluated.stderr[-2000:]
    assert last_json(evaluated.stdout)["ckpt"] == f"{job}/best" and last_json(evaluated.stdout)["method"] == "keyin_plus"


def test_an_optuna_search_runs_its_trials_and_reports_the_best(tmp_path):
    pytest.importorskip("hydra_plugins.hydra_optuna_sweeper")
    assert run("generate", "splits={test: 4}", "progress=false", cwd=tmp_path).returncode == 0
    result = run("train", "-m", "hydra/sweeper=tune", "hydra.sweeper.n_trials=4", "hydra.sweeper.sampler.seed=0",
                 "model=surprise", "scale.lr_surprise=interval(1e-4,1e-2)", "scale=smoke", "logger=none", *QUIET,
                 cwd=tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    (folder,) = (tmp_path / "runs" / "multirun" / "train").iterdir()
    trials = [json.loads(path.read_text()) for path in folder.glob("*/metrics.json")]
    assert len(trials) == 4
    best = yaml.safe_load((folder / "optimization_results.yaml").read_text())
    assert best["best_value"] == pytest.approx(max(trial["val_f1_best"] for trial in trials))
    assert 1e-4 <= best["best_params"]["scale.lr_surprise"] <= 1e-2
