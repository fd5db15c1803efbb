"""Trackers: job names, wandb offline without a login, and a sweep logged to wandb (offline): one run
per job, named by what it changes, one group, the whole config and the results.

The sweep runs as a real ``keyin-train`` process: wandb wraps the process's stdout/stderr for its
console log, which in-process would be pytest's redirected streams.
"""

import json

import pytest

from keyin.cli.naming import job_dir, job_label, safe_name, sweep_group
from keyin.cli.naming import wandb_logged_in
from tests.cli.runner import run, run_process

wandb = pytest.importorskip("wandb")
from tests.cli.wandb_records import offline_run  # noqa: E402


def test_job_names_and_sweep_group():
    assert job_label("surprise", "brownian", 1, "seed=1") == "surprise-brownian-seed1[seed=1]"
    assert job_label("surprise", "brownian", 0, "") == "surprise-brownian-seed0"
    assert job_dir("model=jumpy,seed=1", 3) == "model=jumpy,seed=1" and job_dir("", 3) == "3"
    assert job_dir("ckpt=runs/a b/last.ckpt", 0) == "ckpt=runs_a_b_last.ckpt"  # one folder, whatever the values
    long = safe_name("x=" + "1" * 300)
    assert len(long) == 120 and long != safe_name("x=" + "1" * 299 + "2")
    assert sweep_group("RunMode.MULTIRUN", "runs/multirun/x") == "runs/multirun/x"
    assert sweep_group("RunMode.RUN", "runs/multirun/x") is None


def test_wandb_is_offline_without_a_login(tmp_path, monkeypatch):
    monkeypatch.delenv("WANDB_API_KEY", raising=False)
    monkeypatch.setenv("NETRC", str(tmp_path / "netrc"))
    assert not wandb_logged_in()
    (tmp_path / "netrc").write_text("machine api.wandb.ai\n  login user\n  password 0123\n")
    assert wandb_logged_in()


def test_a_wandb_sweep_makes_one_named_offline_run_per_job_in_one_group(tmp_path, monkeypatch):
    monkeypatch.delenv("WANDB_API_KEY", raising=False)
    monkeypatch.setenv("NETRC", str(tmp_path / "no-netrc"))
    monkeypatch.setenv("WANDB_SILENT", "true")
    assert run("generate", "splits={test: 4}", "progress=false", cwd=tmp_path).returncode == 0
    result = run_process("train", "-m", "model=jumpy,surprise", "scale=smoke", "logger=wandb", "logger.offline=true",
                         "num_workers=0", "trainer.enable_progress_bar=false", "hydra.sweep.dir=sweep", cwd=tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "anonymous" not in result.stderr + result.stdout  # no warning about a setting keyin never gave
    runs = {}
    for model, method in (("jumpy", "jumpy"), ("surprise", "surprise")):
        job = tmp_path / "sweep" / f"model={model},num_workers=0,scale=smoke"
        (record,) = job.glob("wandb/offline-run-*/run-*.wandb")  # one run per job, not one reused by the next
        runs[model] = offline_run(record)
        assert runs[model]["name"] == f"{method}-brownian-seed0[model={model},num_workers=0,scale=smoke]"
        config, summary = runs[model]["config"], runs[model]["summary"]
        assert config["method"] == method and config["model"]["name"] == method and config["seed"] == 0
        assert config["scale_preset"] == "smoke" and config["scale"]["stage2_steps"] == 3  # the Hydra config, nested
        metrics = json.loads((job / "metrics.json").read_text())
        assert summary["test/f1"] == pytest.approx(metrics["f1"])
        assert summary["val/f1_best"] == pytest.approx(metrics["val_f1_best"])
    assert runs["jumpy"]["group"] == runs["surprise"]["group"] == "sweep"
