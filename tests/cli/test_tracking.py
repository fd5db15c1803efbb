"""Trackers: a sweep logged to wandb (offline) gives one run per job, grouped by the sweep.

The sweep runs as a real ``keyin-train`` process: wandb wraps the process's stdout/stderr for its
console log, which in-process would be pytest's redirected streams.
"""

import pytest

from keyin.cli.tracking import job_label, sweep_group, wandb_logged_in
from tests.cli.runner import run, run_process

wandb = pytest.importorskip("wandb")


def test_job_label_and_sweep_group():
    assert job_label("train_surprise_brownian", "seed=1") == "train_surprise_brownian[seed=1]"
    assert job_label("train_surprise_brownian", "") == "train_surprise_brownian"
    assert sweep_group("RunMode.MULTIRUN", "runs/multirun/x") == "runs/multirun/x"
    assert sweep_group("RunMode.RUN", "runs/multirun/x") is None


def test_wandb_is_offline_without_a_login(tmp_path, monkeypatch):
    monkeypatch.delenv("WANDB_API_KEY", raising=False)
    monkeypatch.setenv("NETRC", str(tmp_path / "netrc"))
    assert not wandb_logged_in()
    (tmp_path / "netrc").write_text("machine api.wandb.ai\n  login user\n  password 0123\n")
    assert wandb_logged_in()


def test_a_wandb_sweep_makes_one_offline_run_per_job(tmp_path, monkeypatch):
    monkeypatch.delenv("WANDB_API_KEY", raising=False)
    monkeypatch.setenv("NETRC", str(tmp_path / "no-netrc"))
    monkeypatch.setenv("WANDB_SILENT", "true")
    assert run("generate", "splits={test: 4}", "progress=false", cwd=tmp_path).returncode == 0
    result = run_process("train", "-m", "model=surprise", "scale=smoke", "logger=wandb", "seed=0,1", "num_workers=0",
                         "trainer.enable_progress_bar=false", "hydra.sweep.dir=sweep", cwd=tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    runs = sorted((tmp_path / "sweep").glob("*/wandb/offline-run-*"))
    assert len(runs) == 2, runs  # one run per job, not one run reused by the second job
    ids = {path.name.rsplit("-", 1)[-1] for path in runs}
    assert len(ids) == 2
    for job, seed in (("0", 0), ("1", 1)):  # each run's record carries its own job's name
        record = next((tmp_path / "sweep" / job / "wandb").glob("offline-run-*/run-*.wandb")).read_bytes()
        name = "train_surprise_brownian[logger=wandb,model=surprise,num_workers=0,scale=smoke,seed={}," \
               "trainer.enable_progress_bar=False]"
        assert name.format(seed).encode() in record and name.format(1 - seed).encode() not in record
