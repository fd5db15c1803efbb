"""The committed Table 2 jobs' model configs (docs/results/pushing_table2/scripts/model_configs.py): written from the
training job that stands for each model, and the committed report's rows are the names keyin-report gives them."""

import importlib.util
import json
from pathlib import Path

from omegaconf import OmegaConf

from keyin.eval.planning_report import collect_planning, summarise_planning

ROOT = Path(__file__).resolve().parents[1]
TABLE = ROOT / "docs" / "results" / "pushing_table2"
spec = importlib.util.spec_from_file_location("model_configs", TABLE / "scripts" / "model_configs.py")
model_configs = importlib.util.module_from_spec(spec)
spec.loader.exec_module(model_configs)


def write(path: Path, text: str) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)


def test_each_job_gets_the_config_of_the_training_job_that_stands_for_its_model(tmp_path, capsys):
    checkpoint = "models/pushing_table2/${planner.model}_seed${planner.model_seed}.ckpt"
    write(tmp_path / "jobs/keyin_paper_seed1/config.yaml", f"planner:\n  model: keyin_paper\n  model_seed: 1\n  checkpoint: {checkpoint}\n")
    write(tmp_path / "jobs/surprise_seed1/config.yaml", "planner:\n  checkpoint: runs/s/surprise_seed1/checkpoints/surprise/last.ckpt\n")
    write(tmp_path / "jobs/surprise_seed2/config.yaml", "planner:\n  checkpoint: runs/s/surprise_seed2/checkpoints/surprise/last.ckpt\n")
    write(tmp_path / "jobs/random_seed0/config.yaml", "planner:\n  name: random\n")
    for job in ("keyin_paper_seed1", "surprise_seed1", "surprise_seed2", "random_seed0"):
        write(tmp_path / "jobs" / job / "metrics.json", "{}")
    write(tmp_path / "model_jobs/keyin_paper_seed1/config.yaml", "model:\n  name: keyin_paper\nbackbone:\n  name: ours\n")
    write(tmp_path / "model_jobs/keyin_paper_seed1/metrics.json", json.dumps({"backbone": "ours", "scale": "cpu"}))
    write(tmp_path / "model_jobs/surprise_seed1/config.yaml", "model:\n  name: surprise\n")
    write(tmp_path / "model_jobs/surprise_seed1/metrics.json", json.dumps({"backbone": "ours", "scale": "smoke"}))
    model_configs.main(tmp_path)
    paper = OmegaConf.load(tmp_path / "jobs/keyin_paper_seed1/model_config.yaml")
    assert paper.model.name == "keyin_paper" and dict(paper.choices) == {"backbone": "ours", "scale": "cpu"}
    assert OmegaConf.load(tmp_path / "jobs/surprise_seed1/model_config.yaml").choices.scale == "smoke"  # its run dir
    assert not (tmp_path / "jobs/surprise_seed2/model_config.yaml").exists()
    assert not (tmp_path / "jobs/random_seed0/model_config.yaml").exists()
    printed = capsys.readouterr().out
    assert "random_seed0: plans with no model; none written" in printed
    assert "surprise_seed2: no committed training job stands for runs/s/surprise_seed2" in printed


def test_the_committed_table_names_each_row_as_the_report_does_from_the_committed_jobs():
    committed = (TABLE / "table2.md").read_text(encoding="utf-8").split("\n\n")[2]  # the first table
    names = [line.split(" | ")[0].removeprefix("| ") for line in committed.splitlines()[2:]]
    rows = summarise_planning(collect_planning(TABLE / "jobs"), 0.66)
    assert names == [row.planner for row in rows]
    assert "keyin_paper · backbone=ours scale=cpu" in names and "keyin_paper" not in names  # trained at CPU sizes, ours
