"""Every console script end to end (tiny), and bad inputs giving one clear error line."""

import json
import os

import pytest
import torch

from tests.cli.runner import last_json, run, run_process


@pytest.fixture(scope="module")
def brownian_test_set(tmp_path_factory):
    root = tmp_path_factory.mktemp("cli")
    result = run("generate", "dataset=brownian", "splits={test: 40}", "shard_size=25",
                 "progress=false", cwd=root)
    assert result.returncode == 0, result.stderr
    return root


def test_generate_writes_shards_a_manifest_and_a_run_dir(brownian_test_set):
    folder = brownian_test_set / "data" / "brownian"
    assert sorted(p.name for p in folder.iterdir()) == [
        "manifest.json", "test-00000.h5", "test-00001.h5"]
    runs = list((brownian_test_set / "runs" / "generate_brownian").glob("*/*/metrics.json"))
    assert len(runs) == 1 and json.loads(runs[0].read_text())["clips"] == 40


@pytest.mark.parametrize("model", ["random", "constant", "changepoint"])
def test_eval_baseline_prints_metrics_and_writes_them(brownian_test_set, model):
    result = run("eval", f"model={model}", "progress=false", cwd=brownian_test_set)
    assert result.returncode == 0, result.stderr
    metrics = last_json(result.stdout)
    for key in ("f1", "f1_macro", "f1_tol1", "precision", "recall", "n_sequences"):
        assert 0.0 <= metrics[key] <= (1.0 if key != "n_sequences" else 40)
    assert metrics["n_sequences"] == 40 and metrics["method"] == model
    assert metrics["dataset"] == "brownian"
    machine = metrics["machine"]  # what the job's wall times were measured on
    assert machine["cpus"] == os.cpu_count() and machine["cpu"] and machine["torch"] == torch.__version__
    assert machine["gpu"] == (torch.cuda.get_device_name(0) if torch.cuda.is_available() else None)
    assert machine["torch_threads"] >= 1
    saved = list((brownian_test_set / "runs" / f"eval_{model}_brownian").glob("*/*/metrics.json"))
    assert json.loads(saved[-1].read_text()) == metrics
    assert (saved[-1].parent / "keyframes.png").is_file() and (saved[-1].parent / "keyframes.gif").is_file()


def test_eval_reads_any_file_given_by_path(brownian_test_set):
    shard = brownian_test_set / "data" / "brownian" / "test-00001.h5"
    result = run("eval", "model=constant", f"data={shard}", "progress=false", cwd=brownian_test_set)
    assert result.returncode == 0, result.stderr
    assert last_json(result.stdout)["n_sequences"] == 15


def test_console_scripts_are_installed_next_to_the_interpreter(tmp_path):
    result = run_process("plan", "success_threshold=0", cwd=tmp_path, timeout=60)
    assert result.returncode == 2 and "error: success_threshold=0 must be a positive number" in result.stderr



def test_eval_skips_a_finished_run_dir_when_asked(brownian_test_set):
    first = run("eval", "model=random", "progress=false", "hydra.run.dir=runs/skip", cwd=brownian_test_set)
    again = run("eval", "model=random", "progress=false", "hydra.run.dir=runs/skip", "skip_finished=true", "seed=5",
                cwd=brownian_test_set)
    assert first.returncode == again.returncode == 0, again.stderr
    assert "finished earlier; skipped" in again.stdout and last_json(again.stdout) == last_json(first.stdout)
