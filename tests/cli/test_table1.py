"""The Table 1 sweep end to end at scale=smoke: one multirun, a shared stage 1, skip on re-run, report."""

import json

import pytest

from keyin.cli import report
from tests.cli.runner import run

SWEEP = ("-m", "experiment=brownian_table1", "scale=smoke", "logger=none", "num_workers=0", "trainer.enable_progress_bar=false",
         "model=static,surprise,random", "seed=0")


@pytest.fixture(scope="module")
def sweep(tmp_path_factory):
    root = tmp_path_factory.mktemp("table1")
    result = run("train", *SWEEP, cwd=root)
    assert result.returncode == 0, result.stderr
    return root, root / "runs" / "multirun" / "brownian_table1"


def test_every_job_scores_its_method_and_surprise_reports_both_index_readings(sweep):
    _, folder = sweep
    metrics = {m: json.loads((folder / f"{m}_seed0" / "metrics.json").read_text()) for m in ("static", "surprise", "random")}
    assert all(m["method"] == name and m["seed"] == 0 and m["n_sequences"] == 8 for name, m in metrics.items())
    assert set(metrics["surprise"]["variants"]) == {"surprise_shift0"}
    assert (folder / "stage1_ours_seed0" / "checkpoints" / "interpolator" / "last.ckpt").is_file()
    assert not (folder / "static_seed0" / "checkpoints" / "interpolator").exists()  # stage 1 is shared
    assert (folder / "surprise_seed0" / "checkpoints" / "surprise" / "last.ckpt").is_file()


def test_running_the_sweep_again_skips_finished_jobs(sweep):
    root, folder = sweep
    before = {p: p.stat().st_mtime_ns for p in folder.glob("*/metrics.json")}
    result = run("train", *SWEEP, cwd=root)
    assert result.returncode == 0, result.stderr
    assert result.stdout.count("finished earlier; skipped") == 3
    assert {p: p.stat().st_mtime_ns for p in folder.glob("*/metrics.json")} == before


def test_report_writes_the_table_the_chart_and_the_examples(sweep, capsys):
    _, folder = sweep
    report.main([str(folder), "--examples", "2"])
    table = (folder / "report" / "table1.md").read_text()
    for method, paper in (("random", "0.15"), ("static", "0.21"), ("surprise", "0.73"), ("surprise_shift0", "–")):
        assert f"| brownian | {method} |" in table and f"| {paper} |" in table
    assert (folder / "report" / "table1.csv").read_text().count("\n") == 5
    for picture in ("table1_f1.png", "examples_brownian.png"):
        assert (folder / "report" / picture).stat().st_size > 0


def test_report_of_a_folder_without_results_names_the_fix(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        report.main([str(tmp_path)])
    assert exit_.value.code == 2
    assert "no metrics.json" in capsys.readouterr().err


def test_stage_is_refused_for_a_one_stage_model(tmp_path):
    result = run("train", "model=surprise", "stage=keyframes", "scale=smoke", cwd=tmp_path)
    assert result.returncode == 2 and "drop stage=" in result.stderr
