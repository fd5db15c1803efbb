"""keyin-report's Table 2 on a fabricated keyin-plan sweep folder."""

import json

import numpy as np
import pytest
from hydra import compose, initialize_config_module
from omegaconf import OmegaConf

from keyin.cli import report
from keyin.eval.planning import bootstrap_interval, planning_summary, success_curve
from keyin.cli.app import CONFIG_MODULE
from keyin.eval.planning_report import (
    collect_planning,
    difference_markdown,
    machines_markdown,
    outcome_markdown,
    paired_success_difference,
    planning_csv,
    planning_markdown,
    sensitivity_markdown,
    named_planner,
    success_curves,
    summarise_planning,
)
from keyin.eval.report import model_run


def write_job(root, planner, seed, errors, threshold=0.66, extra_lines="", outcomes=None, machine=None, model_config=None,
              **setting):
    job = root / f"{planner}_seed{seed}{''.join(f'_{value}' for value in setting.values())}"
    job.mkdir(parents=True)
    records = [dict(task=i, planner=planner, seed=seed, final_error=e, initial_distance=1.25, steps=10, subgoals=1,
                    subgoals_used=1, success=e <= threshold, seconds=1.0) for i, e in enumerate(errors)]
    for record, outcome in zip(records, outcomes or []):
        record["outcome"] = outcome
    (job / "tasks.jsonl").write_text("".join(json.dumps(r) + "\n" for r in reversed(records)) + extra_lines)
    metrics = dict(planning_summary(np.array(errors), np.full(len(errors), 1.25), threshold), planner=planner,
                   seed=seed, dataset="pushing", success_threshold=threshold, **setting)
    if machine is not None:
        metrics["machine"] = machine
    (job / "metrics.json").write_text(json.dumps(metrics))
    if model_config is not None:
        (job / "model_config.yaml").write_text(OmegaConf.to_yaml(model_config))


@pytest.fixture
def sweep(tmp_path):
    write_job(tmp_path, "no_subgoals", 0, [0.2, 1.0])
    write_job(tmp_path, "no_subgoals", 1, [0.6, 1.2], outcomes=["success", "not_crossed"])
    write_job(tmp_path, "demo_subgoals", 0, [0.1, 0.1], outcomes=["success", "success"])
    write_job(tmp_path, "initial", 0, [1.25, 1.25], extra_lines='{"task": 9, "final')  # a later run, killed
    return tmp_path


def test_metrics_and_the_curve():
    errors = np.array([0.2, 0.66, 1.0, 1.3])
    np.testing.assert_allclose(success_curve(errors, np.array([0.0, 0.66, 2.0])), [0.0, 0.5, 1.0])
    summary = planning_summary(errors, np.full(4, 1.3), 0.66)
    assert summary["success_rate"] == 0.5 and summary["position_error_std"] == pytest.approx(errors.std())
    assert summary["relative_error_mean"] == pytest.approx(errors.mean() / 1.3) and summary["n_tasks"] == 4


def test_rows_pool_the_tasks_of_every_seed_in_the_papers_order(sweep):
    rows = summarise_planning(collect_planning(sweep), 0.66)
    assert [row.planner for row in rows] == ["initial", "no_subgoals", "demo_subgoals"]
    no_subgoals = rows[1]
    assert no_subgoals.seeds == [0, 1] and no_subgoals.summary["n_tasks"] == 4
    assert no_subgoals.summary["position_error_mean"] == pytest.approx(0.75)
    assert no_subgoals.summary["success_rate"] == 0.5 and no_subgoals.paper == (0.90, 0.14, 15.0)
    markdown = planning_markdown(rows, 0.66)
    assert "| initial | 1.25 ± 0.00 | 1.32 ± 0.06 | 0.0 % [0.0, 0.0] | – | – |" in markdown  # one seed: no spread
    # seeds 0 and 1 succeed on 1 of 2 tasks each: 50 % ± 0 over seeds; every task took 1 s
    assert "| no_subgoals | 0.75 ± 0.38 | 0.90 ± 0.14 | 50.0 % [0.0, 100.0] | 50.0 ± 0.0 % | 15.0 % | 0.60 | 10.0 | 1.0 | 4 | 0 1 |" in markdown
    assert "| demo_subgoals | 0.10 ± 0.00 | – | 100.0 % [100.0, 100.0] | – | – |" in markdown
    lines = planning_csv(rows, 0.66).splitlines()
    assert len(lines) == 4 and lines[0].startswith("planner,seeds,n_tasks,success_threshold,position_error_mean")
    assert lines[2].startswith("no_subgoals,0 1,4,0.66,0.75,") and lines[2].endswith(",0.5 0.5,10,1,0.9,0.14,15.0")


def test_the_spread_over_seeds_is_the_sample_std_of_each_seeds_success_rate(tmp_path):
    for seed, errors in enumerate(([0.1, 0.1, 0.1, 1.0], [0.1, 1.0, 1.0, 1.0], [0.1, 0.1, 1.0, 1.0])):
        write_job(tmp_path, "jumpy", seed, errors)  # 75 %, 25 %, 50 %: std 25 points
    (row,) = summarise_planning(collect_planning(tmp_path), 0.66)
    assert row.seed_success == [0.75, 0.25, 0.5] and row.summary["success_rate"] == 0.5
    assert "| 50.0 % [" in planning_markdown([row], 0.66) and "| 50.0 ± 25.0 % |" in planning_markdown([row], 0.66)


def test_each_rows_wall_time_names_the_machine_of_each_seed(tmp_path):
    xeon = {"cpu": "Intel(R) Xeon(R) Processor", "cpus": 2, "torch_threads": 1, "torch": "2.13.0+cpu", "gpu": None}
    epyc = dict(xeon, cpu="AMD EPYC 7B13")
    write_job(tmp_path, "jumpy", 0, [0.1], machine=epyc)
    write_job(tmp_path, "jumpy", 1, [0.1], machine=xeon)
    write_job(tmp_path, "jumpy", 2, [0.1], machine=xeon)
    write_job(tmp_path, "random", 0, [1.0])  # keyin-plan before the machine was recorded
    rows = summarise_planning(collect_planning(tmp_path), 0.66)
    assert rows[1].machines == {0: "AMD EPYC 7B13, 2 CPUs, torch 2.13.0+cpu", 1: "Intel(R) Xeon(R) Processor, 2 CPUs, torch 2.13.0+cpu",
                                2: "Intel(R) Xeon(R) Processor, 2 CPUs, torch 2.13.0+cpu"}
    assert machines_markdown(rows).splitlines() == [
        "- s / task on AMD EPYC 7B13, 2 CPUs, torch 2.13.0+cpu: jumpy (seeds 0)",
        "- s / task on Intel(R) Xeon(R) Processor, 2 CPUs, torch 2.13.0+cpu: jumpy (seeds 1 2)",
        "- s / task of jobs that did not record their machine: random (seeds 0)",
    ]


def test_the_success_curves_run_from_zero_past_every_error(sweep):
    rows = summarise_planning(collect_planning(sweep), 0.66)
    thresholds, curves = success_curves(rows, points=5)
    np.testing.assert_allclose(thresholds, np.linspace(0.0, 1.6, 5))  # every error is below 1.55
    assert list(curves) == ["initial (2 tasks)", "no_subgoals (4 tasks)", "demo_subgoals (2 tasks)"]
    np.testing.assert_allclose(curves["no_subgoals (4 tasks)"], [0.0, 0.25, 0.5, 1.0, 1.0])  # errors 0.2, 0.6, 1.0, 1.2
    rows[0].errors = np.array([2.0, 1.0])
    assert success_curves(rows)[0][-1] == pytest.approx(2.05)


def test_the_outcome_counts_list_the_rows_that_recorded_them(sweep):
    rows = summarise_planning(collect_planning(sweep), 0.66)
    assert rows[1].outcomes == {"not recorded": 2, "success": 1, "not_crossed": 1}
    table = outcome_markdown(rows).splitlines()
    assert table[0] == ("| planner | success | untouched | reached then lost | not crossed | crossed missed | "
                        "not recorded |")
    assert table[2:] == ["| no_subgoals | 1 | 0 | 0 | 1 | 0 | 2 |", "| demo_subgoals | 2 | 0 | 0 | 0 | 0 | 0 |"]
    assert outcome_markdown(rows[:1]) == ""  # Initial never runs the servo


def test_the_report_writes_table_2_and_the_curve(sweep, capsys):
    report.main([str(sweep)])
    text = (sweep / "report" / "table2.md").read_text()
    assert "| no_subgoals | 0.75 ± 0.38 |" in text and "## How the tasks ended" in text
    assert (sweep / "report" / "table2.csv").is_file() and (sweep / "report" / "table2_success.png").stat().st_size > 0
    assert not (sweep / "report" / "table1.md").exists()
    report.main([str(sweep), "--threshold", "1.1", "--out", str(sweep / "loose")])
    assert "| no_subgoals | 0.75 ± 0.38 | 0.90 ± 0.14 | 75.0 % [" in (sweep / "loose" / "table2.md").read_text()


def test_mixed_thresholds_and_a_planner_seed_twice_are_refused(sweep, capsys):
    write_job(sweep / "other", "random", 0, [1.0], threshold=0.5)
    with pytest.raises(SystemExit):
        report.main([str(sweep)])
    assert "different success thresholds [0.5, 0.66]; choose one with --threshold" in capsys.readouterr().err
    write_job(sweep / "again", "initial", 0, [1.0])
    with pytest.raises(ValueError, match="planner initial with seed 0 appears twice"):
        summarise_planning(collect_planning(sweep), 0.66)


def test_the_success_interval_is_the_binomial_one_for_many_tasks():
    """240 tasks, 213 successes (88.8 %): the normal approximation gives ±1.96·√(p(1−p)/n) = ±4.0 points."""
    successes = np.r_[np.ones(213), np.zeros(27)]
    low, high = bootstrap_interval(successes)
    half = 1.96 * np.sqrt(0.8875 * 0.1125 / 240)
    assert low == pytest.approx(0.8875 - half, abs=0.006) and high == pytest.approx(0.8875 + half, abs=0.006)
    assert bootstrap_interval(np.full(10, 0.3)) == pytest.approx((0.3, 0.3))
    assert bootstrap_interval(successes, seed=3) == bootstrap_interval(successes, seed=3)  # seeded


def test_the_paired_difference_counts_only_the_tasks_both_played(tmp_path):
    write_job(tmp_path, "keyin_plus", 0, [0.1, 0.1, 0.1, 1.0, 0.1])  # succeeds on tasks 0, 1, 2, 4
    write_job(tmp_path, "jumpy", 0, [0.1, 1.0, 0.1, 1.0])  # tasks 0 and 2; task 4 never played
    rows = {row.planner: row for row in summarise_planning(collect_planning(tmp_path), 0.66)}
    difference = paired_success_difference(rows["keyin_plus"], rows["jumpy"], 0.66)
    assert difference["n_tasks"] == 4 and difference["difference"] == pytest.approx(0.25)
    assert difference["low"] <= 0.25 <= difference["high"]
    same = paired_success_difference(rows["jumpy"], rows["jumpy"], 0.66)
    assert (same["difference"], same["low"], same["high"]) == (0.0, 0.0, 0.0)
    line = difference_markdown(list(rows.values()), 0.66)
    assert line.startswith("- keyin_plus − jumpy success: +25.0 points, 95 % paired bootstrap interval [")
    assert difference_markdown([rows["keyin_plus"]], 0.66) == ""


def test_the_baselines_are_paired_too(tmp_path):
    write_job(tmp_path, "tap", 0, [0.1, 1.0, 0.1])
    write_job(tmp_path, "no_subgoals", 0, [1.0, 1.0, 1.0])
    rows = summarise_planning(collect_planning(tmp_path), 0.66)
    assert difference_markdown(rows, 0.66).startswith("- tap − no_subgoals success: +66.7 points")


def test_a_servo_setting_is_its_own_row_and_the_sensitivity_table_pairs_the_tasks(tmp_path):
    write_job(tmp_path, "jumpy", 0, [0.1, 0.1, 1.0, 0.1])  # no setting recorded: state, servo steps
    write_job(tmp_path, "jumpy", 0, [0.1, 1.0, 1.0], servo_observe="pixels", servo_action_repeat=2)  # tasks 0-2
    write_job(tmp_path, "jumpy", 0, [1.0, 1.0, 1.0, 1.0], servo_observe="state", servo_action_repeat=1)
    write_job(tmp_path, "no_subgoals", 0, [1.0, 1.0])
    rows = summarise_planning(collect_planning(tmp_path), 0.66)
    assert [row.planner for row in rows] == ["no_subgoals", "jumpy", "jumpy · pixels · servo steps", "jumpy · state · env steps"]
    assert [row.base for row in rows] == ["no_subgoals", "jumpy", "jumpy", "jumpy"] and rows[1].paper == rows[2].paper
    table = sensitivity_markdown(rows, 0.66)
    header, _, line = table.splitlines()
    assert header == "| planner | state · servo steps | pixels · servo steps | state · env steps | common tasks |"
    # on the 3 tasks every setting played: 2, 1 and 0 successes
    assert line.startswith("| jumpy | 66.7 % [") and "| 33.3 % [" in line and "| 0.0 % [0.0, 0.0] | 3 |" in line
    assert sensitivity_markdown([rows[0], rows[1]], 0.66) == ""  # no planner in two settings
    report.main([str(tmp_path), "--out", str(tmp_path / "out")])
    assert "## Servo settings" in (tmp_path / "out" / "table2.md").read_text()


def test_a_longer_servo_plan_is_its_own_setting(tmp_path):
    write_job(tmp_path, "no_subgoals", 0, [1.0, 1.0, 0.1])  # recorded no horizon: the paper's l = 8
    write_job(tmp_path, "no_subgoals", 0, [0.1, 1.0, 0.1], servo_horizon=16)
    write_job(tmp_path, "no_subgoals", 0, [0.1, 0.1, 0.1], servo_horizon=8)  # l = 8 recorded: the default row
    with pytest.raises(ValueError, match="appears twice"):
        summarise_planning(collect_planning(tmp_path), 0.66)
    (tmp_path / "no_subgoals_seed0_8").rename(tmp_path.parent / "elsewhere")  # the recorded l = 8 job
    rows = summarise_planning(collect_planning(tmp_path), 0.66)
    assert [row.planner for row in rows] == ["no_subgoals", "no_subgoals · state · servo steps · plans of 16 actions"]


def test_one_model_under_other_planning_seeds_is_its_own_row_and_not_a_servo_setting(tmp_path):
    write_job(tmp_path, "keyin_paper", 0, [0.1, 0.1, 0.1, 0.1], model_seed=0)  # planned with its own model
    write_job(tmp_path, "keyin_paper", 1, [0.1, 1.0, 1.0, 0.1], model_seed=1)
    write_job(tmp_path / "noise", "keyin_paper", 1, [0.1, 0.1, 1.0, 0.1], model_seed=0)  # model 0, planning seed 1
    write_job(tmp_path / "noise", "keyin_paper", 2, [1.0, 0.1, 0.1, 0.1], model_seed=0)
    write_job(tmp_path, "keyin_paper", 0, [0.1, 1.0], servo_observe="pixels", servo_action_repeat=2, model_seed=0)
    rows = summarise_planning(collect_planning(tmp_path), 0.66)  # no job recorded its model's config
    assert [row.planner for row in rows] == ["keyin_paper · model not recorded",
                                             "keyin_paper · model not recorded · pixels · servo steps",
                                             "keyin_paper · model not recorded · model seed 0"]
    assert [row.model_seed for row in rows] == [None, None, 0]
    assert rows[2].seeds == [1, 2] and rows[2].seed_success == [0.75, 0.75] and rows[0].seed_success == [1.0, 0.5]
    header, _, line = sensitivity_markdown(rows, 0.66).splitlines()
    assert "model seed" not in header and line.endswith("| 2 |")  # seed 0's tasks 0 and 1 in both servo settings


def test_a_row_of_the_papers_method_names_what_its_model_changed_beside_the_papers_figures(tmp_path):
    ours = {"choices": {"backbone": "ours", "scale": "cpu"}, "backbone": {"name": "ours"}, "model": {"name": "keyin_paper"}}
    stated = {"choices": {"backbone": "paper", "scale": "paper"}, "model": {"keyframes": {"lr": 2e-4}}}
    before_choices = {"backbone": {"name": "paper"}, "model": {"keyframes": {"lr": 1e-3}}}  # a checkpoint from before choices were recorded
    write_job(tmp_path / "ours", "keyin_paper", 0, [0.1, 1.0, 0.1, 0.1], model_config=ours)
    write_job(tmp_path / "ours", "keyin_paper", 1, [0.1, 1.0, 1.0, 0.1], model_config=ours)
    write_job(tmp_path / "stated", "keyin_paper", 0, [0.1, 0.1, 0.1, 0.1], model_config=stated)
    write_job(tmp_path / "older", "keyin_paper", 0, [1.0, 1.0, 1.0, 0.1], model_config=before_choices)
    write_job(tmp_path / "ours", "jumpy", 0, [1.0, 1.0, 0.1, 0.1], model_config=dict(ours, model={"name": "jumpy"}))
    write_job(tmp_path / "ours", "keyin_paper", 0, [0.1, 1.0], servo_observe="pixels", model_config=ours)
    write_job(tmp_path / "plain", "no_subgoals", 0, [1.0, 1.0, 1.0, 1.0])  # plans with no model
    write_job(tmp_path / "elsewhere", "keyin_paper", 2, [0.1, 0.1])  # seed 2: shares no (seed, task) with Jumpy's
    rows = summarise_planning(collect_planning(tmp_path), 0.66)
    assert [row.planner for row in rows] == [
        "no_subgoals", "jumpy", "keyin_paper", "keyin_paper · backbone=ours scale=cpu",
        "keyin_paper · model not recorded", "keyin_paper · model.keyframes.lr=0.001",
        "keyin_paper · backbone=ours scale=cpu · pixels · servo steps"]
    assert [row.seeds for row in rows[2:6]] == [[0], [0, 1], [2], [0]]
    assert {row.paper for row in rows[2:]} == {(0.50, 0.26, 64.2)} and rows[1].paper == (0.62, 0.33, 58.8)
    lines = difference_markdown(rows, 0.66).splitlines()  # each keyin_paper row against Jumpy where they share tasks
    assert [line.split(" success:")[0] for line in lines] == [
        "- keyin_paper − jumpy", "- keyin_paper · backbone=ours scale=cpu − jumpy", "- keyin_paper · model.keyframes.lr=0.001 − jumpy"]
    assert lines[0].startswith("- keyin_paper − jumpy success: +50.0 points") and "over 4 common tasks" in lines[1]


def pushing_cpu_scale() -> dict:
    """scale=cpu with dataset=pushing's own values, as keyin-train composes them."""
    with initialize_config_module(config_module=CONFIG_MODULE, version_base="1.3"):
        cfg = compose(config_name="train", overrides=["dataset=pushing", "scale=cpu"])
    return OmegaConf.to_container(cfg.scale, resolve=True)


def test_a_model_that_recorded_no_choices_is_named_by_the_preset_its_sizes_are():
    scale = pushing_cpu_scale()
    older = OmegaConf.create({"backbone": {"name": "ours"}, "dataset": {"name": "pushing"}, "scale": scale})
    assert model_run(older) == {"backbone": "ours", "scale": "cpu"}
    assert named_planner("keyin_paper", older) == "keyin_paper · backbone=ours scale=cpu"
    brownian = OmegaConf.merge(older, {"dataset": {"name": "brownian"}})  # pushing's conv_width 8 is not Brownian's cpu
    assert model_run(brownian)["scale"] is None
    overridden = OmegaConf.merge(older, {"scale": {"lstm_hidden": 256}})  # scale.lstm_hidden=256: no preset
    assert named_planner("keyin_paper", overridden) == "keyin_paper · backbone=ours"
    assert named_planner("jumpy", overridden) == "jumpy" and named_planner("jumpy", None) == "jumpy"


@pytest.mark.parametrize("text, problem", [("model: [unclosed", "is not YAML"), ("", "holds no run config"),
                                           ("- a list\n", "holds no run config")])
def test_a_broken_model_config_is_refused_naming_the_file(tmp_path, text, problem):
    write_job(tmp_path, "keyin_paper", 0, [0.1])
    (tmp_path / "keyin_paper_seed0" / "model_config.yaml").write_text(text)
    with pytest.raises(ValueError, match=f"keyin_paper_seed0/model_config.yaml {problem}.*; plan the job again"):
        collect_planning(tmp_path)
