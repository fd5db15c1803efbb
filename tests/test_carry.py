"""The stated configuration's carried checkpoint (docs/results/keyin_paper_stated/scripts/carry.py): Adam's moments
travel in bfloat16 and come back as the weights' float32, the weights and the step exactly."""

import importlib.util
import json
from pathlib import Path

import lightning as L
import pytest
import torch
from lightning.pytorch.callbacks import ModelCheckpoint

from tests.lit.test_fit_stage import Line, Numbers  # a one-weight module and its data

SCRIPT = Path(__file__).resolve().parents[1] / "docs" / "results" / "keyin_paper_stated" / "scripts" / "carry.py"
spec = importlib.util.spec_from_file_location("carry", SCRIPT)
carry = importlib.util.module_from_spec(spec)
spec.loader.exec_module(carry)


@pytest.fixture
def repo(tmp_path, monkeypatch):
    """carry.py writing into a checkout under tmp_path, its manifest empty."""
    monkeypatch.setattr(carry, "ROOT", tmp_path)
    monkeypatch.setattr(carry, "FOLDER", tmp_path / "models" / "in_progress")
    monkeypatch.setattr(carry, "MANIFEST", tmp_path / "models" / "manifest.json")
    monkeypatch.setattr(carry, "RECORDS", tmp_path / "docs" / "jobs")
    carry.MANIFEST.parent.mkdir(parents=True)
    carry.MANIFEST.write_text('{"models": []}')
    return tmp_path


def test_a_slimmed_checkpoint_resumes_adam_with_its_moments_to_bfloat16_precision(tmp_path):
    torch.manual_seed(0)
    net = torch.nn.Linear(8, 4)
    adam = torch.optim.Adam(net.parameters(), lr=2e-4)
    for _ in range(3):
        adam.zero_grad()
        net(torch.randn(16, 8)).pow(2).mean().backward()
        adam.step()
    checkpoint = {"state_dict": {k: v.clone() for k, v in net.state_dict().items()}, "optimizer_states": [adam.state_dict()], "global_step": 3}
    before = {i: {k: v.clone() for k, v in s.items()} for i, s in adam.state_dict()["state"].items()}
    torch.save(carry.slimmed(checkpoint), tmp_path / "last.ckpt")
    loaded = torch.load(tmp_path / "last.ckpt", weights_only=False)
    assert loaded["optimizer_states"][0]["state"][0]["exp_avg"].dtype == torch.bfloat16
    assert all(torch.equal(loaded["state_dict"][k], v) for k, v in net.state_dict().items())
    resumed = torch.optim.Adam(net.parameters(), lr=2e-4)
    resumed.load_state_dict(loaded["optimizer_states"][0])
    for index, state in resumed.state_dict()["state"].items():
        assert float(state["step"]) == 3.0
        for key in ("exp_avg", "exp_avg_sq"):
            assert state[key].dtype == torch.float32
            torch.testing.assert_close(state[key], before[index][key], rtol=1e-2, atol=0)


def test_restore_puts_the_carried_file_where_the_job_resumes_and_never_over_a_newer_one(tmp_path, monkeypatch):
    monkeypatch.setattr(carry, "ROOT", tmp_path)
    monkeypatch.setattr(carry, "FOLDER", tmp_path / "models" / "in_progress")
    carry.FOLDER.mkdir(parents=True)
    torch.save({"global_step": 2000}, carry.FOLDER / "stated_seed0_stage1_last.ckpt")
    jobs = tmp_path / "jobs"
    carry.restore(jobs, "stated_seed0")
    target = carry.job_checkpoint(jobs, "stated_seed0")
    assert torch.load(target, weights_only=False) == {"global_step": 2000}
    target.write_bytes(b"newer")
    carry.restore(jobs, "stated_seed0")
    assert target.read_bytes() == b"newer"


def test_a_stage_2_job_is_carried_under_its_own_name_and_restored_to_its_keyframes_checkpoint(tmp_path, repo):
    jobs = tmp_path / "jobs"
    (jobs / "stated_stage2_seed1" / ".hydra").mkdir(parents=True)
    (jobs / "stated_stage2_seed1" / ".hydra" / "config.yaml").write_text("model:\n  name: keyin_paper_stated_10k_5k\n")
    source = carry.job_checkpoint(jobs, "stated_stage2_seed1", "keyframes")
    source.parent.mkdir(parents=True)
    torch.save({"state_dict": {"w": torch.ones(2)}, "optimizer_states": [], "global_step": 500}, source)
    target = carry.save(jobs, "stated_stage2_seed1", "keyframes")
    assert target.name == "stated_stage2_seed1_stage2_last.ckpt"
    entry = json.loads(carry.MANIFEST.read_text())["models"][0]
    assert (entry["stage"], entry["model"], entry["path"]) == ("keyframes", "keyin_paper_stated_10k_5k", "models/in_progress/stated_stage2_seed1_stage2_last.ckpt")
    recorded = json.loads((carry.RECORDS / "stated_stage2_seed1" / "checkpoints.json").read_text())
    assert recorded["checkpoints/keyframes/last.ckpt"]["global_step"] == 500 and recorded["carried"]["path"] == entry["path"]
    source.unlink()
    carry.restore(jobs, "stated_stage2_seed1", "keyframes")
    assert torch.load(source, weights_only=False)["global_step"] == 500


def test_a_resumed_runs_rows_replace_the_steps_it_repeats_and_every_earlier_step_is_kept():
    def rows(*steps):
        return [{"step": str(step), "train/loss": f"{step}.0"} for step in steps]

    committed, lost_after_checkpoint, resumed = rows(24, 49, 499, 524), rows(549), rows(524, 549, 574)
    merged = carry.merged_rows([committed, [], resumed])
    assert [row["step"] for row in merged] == ["24", "49", "499", "524", "549", "574"]
    assert carry.merged_rows([committed + lost_after_checkpoint, resumed]) == merged  # the lost run's 549 replaced


def test_the_test_row_at_step_0_of_a_finished_run_keeps_the_earlier_runs_rows_and_replaces_an_earlier_test_row():
    def rows(*steps):
        return [{"step": str(step), "train/loss": f"{step}.0", "test/f1": ""} for step in steps]

    def tested(f1):
        return {"step": "0", "train/loss": "", "test/f1": f1}

    earlier, finished = rows(999, 1999, 2499), rows(2524, 4999) + [tested("0.137")]
    merged = carry.merged_rows([earlier, finished])
    assert [(row["step"], row["test/f1"]) for row in merged] == [
        ("999", ""), ("1999", ""), ("2499", ""), ("2524", ""), ("4999", ""), ("0", "0.137")]
    again = carry.merged_rows([merged, rows(4999) + [tested("0.140")]])  # the same end scored again
    assert [(row["step"], row["test/f1"]) for row in again][-2:] == [("4999", ""), ("0", "0.140")] and len(again) == 6


def test_save_records_the_jobs_config_and_metrics_across_its_runs_beside_its_checkpoint_hashes(tmp_path, repo):
    jobs, job = tmp_path / "jobs", "stated_seed0"
    (jobs / job / ".hydra").mkdir(parents=True)
    (jobs / job / ".hydra" / "config.yaml").write_text("model:\n  name: keyin_paper_stated_20k\n")
    folder = carry.RECORDS / job
    folder.mkdir(parents=True)
    (folder / "stage1_metrics.csv").write_text("epoch,step,train/loss\n0,24,9.0\n0,49,8.0\n")
    (folder / "checkpoints.json").write_text('{"note": "in progress"}')
    for version, text in ((0, "epoch,step,train/loss,val/bce\n0,49,7.5,\n0,49,,3.0\n"), (1, "epoch,step,train/loss\n0,74,7.0\n")):
        (jobs / job / "csv" / f"version_{version}").mkdir(parents=True)
        (jobs / job / "csv" / f"version_{version}" / "metrics.csv").write_text(text)
    source = carry.job_checkpoint(jobs, job)
    source.parent.mkdir(parents=True)
    torch.save({"state_dict": {"w": torch.ones(2)}, "optimizer_states": [], "global_step": 50}, source)
    carry.save(jobs, job)
    assert (folder / "stage1_metrics.csv").read_text() == (
        "epoch,step,train/loss,val/bce\n0,24,9.0,\n0,49,7.5,\n0,49,,3.0\n0,74,7.0,\n")
    assert (folder / "config.yaml").read_text() == "model:\n  name: keyin_paper_stated_20k\n"  # the job's composed config
    cards = json.loads((folder / "checkpoints.json").read_text())
    assert cards["note"] == "in progress" and cards["checkpoints/interpolator/last.ckpt"]["global_step"] == 50
    assert cards["carried"]["sha256"] == carry.sha256_of(carry.carried(job))


PUBLISH = SCRIPT.with_name("publish.py")
publish_spec = importlib.util.spec_from_file_location("publish", PUBLISH)
publish = importlib.util.module_from_spec(publish_spec)
publish_spec.loader.exec_module(publish)


def job_folders(jobs: Path, rows: dict[str, str]) -> None:
    """A run folder per job, its Hydra config naming its row, and a last checkpoint."""
    for job, name in rows.items():
        (jobs / job / ".hydra").mkdir(parents=True)
        (jobs / job / ".hydra" / "config.yaml").write_text(f"model:\n  name: {name}\n")
        (jobs / job / "checkpoints").mkdir()
        (jobs / job / "checkpoints" / "last.ckpt").write_bytes(job.encode())


def test_publish_copies_finished_seeds_under_their_row_name_and_refuses_an_unfinished_one(tmp_path):
    jobs = tmp_path / "jobs"
    job_folders(jobs, {"stated_seed0": "keyin_paper_stated_20k", "stated_stage2_seed0": "keyin_paper_stated_10k_5k",
                       "stated_stage2_seed1": "keyin_paper_stated_10k_5k"})
    (jobs / "stated_stage2_seed0" / "metrics.json").write_text('{"f1": 0.1}')
    with pytest.raises(SystemExit, match="seed 1 has not finished"):
        publish.publish(jobs, [0, 1], tmp_path / "table")
    copied = publish.publish(jobs, [0], tmp_path / "table")
    assert sorted(copied) == ["keyin_paper_stated_10k_5k_seed0", "keyin_paper_stated_stage1_seed0"]
    row = tmp_path / "table" / "jobs" / "keyin_paper_stated_10k_5k_seed0"
    assert json.loads((row / "metrics.json").read_text()) == {"f1": 0.1}
    assert (row / "config.yaml").read_text() == "model:\n  name: keyin_paper_stated_10k_5k\n"
    assert list(json.loads((row / "checkpoints.json").read_text())) == ["checkpoints/last.ckpt"]


def test_publish_takes_a_longer_budgets_job_under_its_own_row(tmp_path):
    jobs = tmp_path / "jobs"
    job_folders(jobs, {"stated_seed0": "keyin_paper_stated_20k", "stated_stage2_seed0": "keyin_paper_stated_10k_5k",
                       "stated_stage2_seed0_20k": "keyin_paper_stated_10k_20k"})
    for job in ("stated_stage2_seed0", "stated_stage2_seed0_20k"):
        (jobs / job / "metrics.json").write_text('{"f1": 0.2}')
    named = publish.job_names(jobs, [0], steps=20000)
    assert named == {"keyin_paper_stated_stage1_seed0": jobs / "stated_seed0",
                     "keyin_paper_stated_10k_20k_seed0": jobs / "stated_stage2_seed0_20k"}
    with pytest.raises(SystemExit, match="stated_stage2_seed0_40k/metrics.json is missing"):
        publish.job_names(jobs, [0], steps=40000)


def test_extend_goes_on_from_the_finished_job_under_the_longer_rows_name_and_never_over_its_own_checkpoint(tmp_path):
    jobs = tmp_path / "jobs"
    with pytest.raises(SystemExit, match="finish stated_stage2_seed0 first"):
        carry.extend(jobs, "stated_stage2_seed0_20k", "keyframes", "stated_stage2_seed0", "keyin_paper_stated_10k_20k")
    source = carry.job_checkpoint(jobs, "stated_stage2_seed0", "keyframes")
    source.parent.mkdir(parents=True)
    weights = {"w": torch.arange(3.0)}
    torch.save({"state_dict": weights, "global_step": 5000, carry.CONFIG_KEY: {"model": {"name": "keyin_paper_stated_10k_5k"}}}, source)
    carry.extend(jobs, "stated_stage2_seed0_20k", "keyframes", "stated_stage2_seed0", "keyin_paper_stated_10k_20k")
    target = carry.job_checkpoint(jobs, "stated_stage2_seed0_20k", "keyframes")
    extended = torch.load(target, weights_only=False)
    assert extended["global_step"] == 5000 and torch.equal(extended["state_dict"]["w"], weights["w"])
    assert extended[carry.CONFIG_KEY]["model"]["name"] == "keyin_paper_stated_10k_20k"
    assert torch.load(source, weights_only=False)[carry.CONFIG_KEY]["model"]["name"] == "keyin_paper_stated_10k_5k"
    torch.save({"global_step": 6500}, target)  # the longer job has gone on: extend leaves it
    carry.extend(jobs, "stated_stage2_seed0_20k", "keyframes", "stated_stage2_seed0", "keyin_paper_stated_10k_20k")
    assert torch.load(target, weights_only=False) == {"global_step": 6500}


def fit_line(folder: Path, steps: int, resume: Path | None = None) -> None:
    """Lightning's own ``last.ckpt`` every 2 steps (its version counter on, as in the commits the jobs run)."""
    data = torch.utils.data.DataLoader(Numbers(), batch_size=4)
    checkpoints = ModelCheckpoint(dirpath=folder, save_last=True, save_top_k=0, every_n_train_steps=2)
    trainer = L.Trainer(max_steps=steps, callbacks=[checkpoints], logger=False, enable_progress_bar=False,
                        enable_model_summary=False, accelerator="cpu")
    trainer.fit(Line(), data, ckpt_path=resume)


def test_an_extended_or_restored_job_saves_over_its_own_last_checkpoint_not_beside_it(tmp_path, repo):
    jobs = tmp_path / "jobs"
    source = carry.job_checkpoint(jobs, "stated_stage2_seed0", "keyframes")
    fit_line(source.parent, 4)
    checkpoint = torch.load(source, weights_only=False)
    checkpoint[carry.CONFIG_KEY] = {"model": {"name": "keyin_paper_stated_10k_5k"}}
    torch.save(checkpoint, source)
    carry.extend(jobs, "stated_stage2_seed0_20k", "keyframes", "stated_stage2_seed0", "keyin_paper_stated_10k_20k")
    target = carry.job_checkpoint(jobs, "stated_stage2_seed0_20k", "keyframes")
    fit_line(target.parent, 6, resume=target)
    assert [p.name for p in target.parent.iterdir()] == ["last.ckpt"]
    assert torch.load(target, weights_only=False)["global_step"] == 6

    versioned = target.with_name("last-v1.ckpt")  # a carried file Lightning had saved beside last.ckpt
    checkpoint = torch.load(target, weights_only=False)
    for state in checkpoint["callbacks"].values():
        state["last_model_path"] = str(versioned)
    carry.FOLDER.mkdir(parents=True)
    carry.write_checkpoint(carry.carried("stated_stage2_seed0_20k", "keyframes"), checkpoint)
    target.unlink()  # the machine replaced
    carry.restore(jobs, "stated_stage2_seed0_20k", "keyframes")
    fit_line(target.parent, 8, resume=target)
    assert [p.name for p in target.parent.iterdir()] == ["last.ckpt"]
    assert torch.load(target, weights_only=False)["global_step"] == 8
