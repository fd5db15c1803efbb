"""The committed Table 2 jobs' model configs (docs/results/pushing_table2/scripts/model_configs.py): each the run config
of the committed file its recorded hash names; and the committed report's rows are the names keyin-report gives them."""

import importlib.util
import itertools
import json
from pathlib import Path

from omegaconf import OmegaConf

from keyin.eval.planning_report import collect_planning, summarise_planning

ROOT = Path(__file__).resolve().parents[1]
TABLE = ROOT / "docs" / "results" / "pushing_table2"
spec = importlib.util.spec_from_file_location("model_configs", TABLE / "scripts" / "model_configs.py")
model_configs = importlib.util.module_from_spec(spec)
spec.loader.exec_module(model_configs)


def test_each_job_gets_the_run_config_of_the_committed_file_its_recorded_hash_names(tmp_path, capsys, monkeypatch):
    shipped = model_configs.registry()["pushing"]["sha256"]
    jobs = {"keyin_plus_seed0": {"pretrained:pushing": shipped}, "tap_seed0": {"docs/old/after_seed0.ckpt": "ab" * 32},
            "surprise_seed1": {}, "kept_seed0": {"pretrained:pushing": shipped}}
    for name, recorded in jobs.items():
        (tmp_path / "jobs" / name).mkdir(parents=True)
        (tmp_path / "jobs" / name / "metrics.json").write_text("{}")
        (tmp_path / "jobs" / name / "checkpoints.json").write_text(json.dumps(recorded))
    (tmp_path / "jobs" / "kept_seed0" / "model_config.yaml").write_text("model: {name: written_by_keyin_plan}\n")
    monkeypatch.setattr(model_configs, "MANIFEST", tmp_path / "manifest.json")
    (tmp_path / "manifest.json").write_text(json.dumps({"models": []}))  # the TAP file is not committed here
    model_configs.main(tmp_path)
    written = OmegaConf.load(tmp_path / "jobs/keyin_plus_seed0/model_config.yaml")
    assert written.model.name == "keyin_plus" and written.dataset.name == "pushing"  # the shipped model's stored config
    assert OmegaConf.load(tmp_path / "jobs/kept_seed0/model_config.yaml").model.name == "written_by_keyin_plan"
    assert not (tmp_path / "jobs/tap_seed0/model_config.yaml").exists()
    assert not (tmp_path / "jobs/surprise_seed1/model_config.yaml").exists()
    printed = capsys.readouterr().out
    assert "tap_seed0: planned with docs/old/after_seed0.ckpt (sha256 abababababab), not committed" in printed
    assert "surprise_seed1: records no checkpoint hash; none written" in printed


def report_rows(markdown: str) -> list[str]:
    """The row names of the first table in a Table 2 report."""
    lines = markdown.splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("| planner |")) + 2  # past the header and rule
    return [line.split(" | ")[0].removeprefix("| ") for line in itertools.takewhile(lambda line: line.startswith("|"), lines[start:])]


def test_the_committed_table_names_each_row_as_the_report_does_from_the_committed_jobs():
    names = report_rows((TABLE / "table2.md").read_text(encoding="utf-8"))
    rows = summarise_planning(collect_planning(TABLE / "jobs"), 0.66)
    assert names == [row.planner for row in rows]
    assert "keyin_paper · backbone=ours scale=cpu" in names and "keyin_paper" not in names  # trained at CPU sizes, ours
