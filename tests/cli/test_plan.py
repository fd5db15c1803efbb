"""keyin-plan end to end on three planning tasks with tiny budgets: the planners, resuming, errors."""

import json

import numpy as np
import pytest

from keyin.data.hdf5 import load_arrays, split_files
from keyin.eval.planning import OUTCOMES
from tests.cli.runner import error_line, last_json, run

TINY = ("planner.servo_samples=16", "planner.elites=4", "planner.cem_iterations=1", "planner.max_timesteps=3",
        "progress=false")


@pytest.fixture(scope="module")
def root(tmp_path_factory):
    root = tmp_path_factory.mktemp("plan")
    result = run("generate", "dataset=pushing", "splits={planning: 3}", "progress=false", cwd=root)
    assert result.returncode == 0, result.stderr
    return root


def journal(folder):
    return [json.loads(line) for line in (folder / "tasks.jsonl").read_text().splitlines()]


def test_initial_reproduces_each_tasks_initial_distance(root):
    result = run("plan", "planner=initial", "hydra.run.dir=initial", *TINY, cwd=root)
    assert result.returncode == 0, result.stderr
    expected = load_arrays(split_files(root / "data" / "pushing", "planning")[0])["initial_distance"]
    records = journal(root / "initial")
    assert [r["task"] for r in records] == [0, 1, 2]
    np.testing.assert_allclose([r["final_error"] for r in records], expected, rtol=0, atol=1e-12)
    metrics = last_json(result.stdout)
    assert metrics["n_tasks"] == 3 and metrics["steps_mean"] == 0 and metrics["relative_error_mean"] == pytest.approx(1)
    assert metrics["position_error_mean"] == pytest.approx(expected.mean()) and metrics["success_rate"] == 0.0
    assert json.loads((root / "initial" / "metrics.json").read_text()) == metrics


@pytest.mark.parametrize("planner,subgoals", [("random", 0), ("no_subgoals", 1), ("demo_subgoals", 7)])
def test_planners_run_end_to_end(root, planner, subgoals):
    result = run("plan", f"planner={planner}", f"hydra.run.dir={planner}", "tasks=2", *TINY, cwd=root)
    assert result.returncode == 0, result.stderr
    metrics = last_json(result.stdout)
    assert metrics["planner"] == planner and metrics["n_tasks"] == 2 and metrics["success_threshold"] == 0.66
    for record in journal(root / planner):
        assert record["planner"] == planner and record["steps"] == 3 and record["subgoals"] == subgoals
        assert 0 <= record["final_error"] < 2 and record["success"] == (record["final_error"] <= 0.66)
        if subgoals:  # a servo episode says how it ended
            assert record["outcome"] in OUTCOMES and (record["outcome"] == "success") == record["success"]
            assert record["closest_error"] <= record["final_error"] and record["puck_moved"] >= 0
    records = journal(root / planner)
    first_of_kind = {}
    for record in records if subgoals else []:  # servo episodes only
        first_of_kind.setdefault(record["outcome"], record["task"])
    drawn = [f"task00{i}.{ext}" for i in (0, 1) for ext in ("gif", "png")] if subgoals else []
    drawn += [f"outcome_{kind}_task{i:03d}.{ext}" for kind, i in first_of_kind.items() for ext in ("gif", "png")]
    assert sorted(path.name for path in (root / planner / "pictures").glob("*")) == sorted(drawn)


def test_each_outcome_kind_gets_one_picture_even_where_no_task_is_asked_for(root):
    result = run("plan", "planner=demo_subgoals", "hydra.run.dir=outcomes", "pictures=0", *TINY, cwd=root)
    assert result.returncode == 0, result.stderr
    kinds = [record["outcome"] for record in journal(root / "outcomes")]
    expected = sorted(f"outcome_{kind}_task{kinds.index(kind):03d}.png" for kind in set(kinds))
    assert sorted(path.name for path in (root / "outcomes" / "pictures").glob("*.png")) == expected
    off = run("plan", "planner=demo_subgoals", "hydra.run.dir=no_outcomes", "pictures=0", "outcome_pictures=false",
              "tasks=1", *TINY, cwd=root)
    assert off.returncode == 0, off.stderr
    assert len(journal(root / "no_outcomes")) == 1 and not list((root / "no_outcomes" / "pictures").glob("*"))


def test_the_pixel_servo_and_the_env_step_budget_run_end_to_end(root):
    overrides = ("planner=demo_subgoals", "planner.servo_observe=pixels", "planner/low_level@planner=servo_env_steps")
    result = run("plan", *overrides, "hydra.run.dir=pixels", "tasks=2", "pictures=0", *TINY, cwd=root)
    assert result.returncode == 0, result.stderr
    settings = json.loads((root / "pixels" / "plan.json").read_text())["planner"]
    assert settings["servo_observe"] == "pixels" and settings["servo_action_repeat"] == 1
    metrics = last_json(result.stdout)  # what keyin-report names the row by
    assert (metrics["servo_observe"], metrics["servo_action_repeat"]) == ("pixels", 1)
    records = journal(root / "pixels")
    assert [r["task"] for r in records] == [0, 1] and all(r["steps"] == 3 and r["subgoals"] == 7 for r in records)


def test_a_list_of_tasks_replays_those_tasks_with_their_pictures(root):
    result = run("plan", "planner=no_subgoals", "hydra.run.dir=chosen", "tasks=[2,0]", "pictures=[2]",
                 "outcome_pictures=false", *TINY, cwd=root)
    assert result.returncode == 0, result.stderr
    assert sorted(r["task"] for r in journal(root / "chosen")) == [0, 2]
    assert sorted(path.name for path in (root / "chosen" / "pictures").glob("*")) == ["task002.gif", "task002.png"]


def test_a_resumed_run_redoes_no_finished_task_and_drops_a_partial_line(root):
    first = run("plan", "planner=random", "hydra.run.dir=resumed", "tasks=2", *TINY, cwd=root)
    assert first.returncode == 0, first.stderr
    path = root / "resumed" / "tasks.jsonl"
    records = journal(root / "resumed")
    records[0]["final_error"] = 0.5  # a redone task would get its true error back
    path.write_text("".join(json.dumps(r) + "\n" for r in records) + '{"task": 2, "final_err')  # killed mid-line
    again = run("plan", "planner=random", "resume=resumed", *TINY, cwd=root)
    assert again.returncode == 0, again.stderr
    metrics = last_json(again.stdout)
    assert (metrics["skipped"], metrics["played"], metrics["partial_lines_dropped"]) == (2, 1, 1)
    assert "2 of 3 tasks finished earlier" in again.stdout
    resumed = journal(root / "resumed")
    assert [r["task"] for r in resumed] == [0, 1, 2] and resumed[:2] == records
    assert metrics["success_rate"] == pytest.approx(1 / 3)  # the fabricated 0.5 counts


def test_workers_give_the_same_results(root):
    for folder, workers in (("two_workers", 2), ("one_worker", 1)):
        result = run("plan", "planner=random", f"hydra.run.dir={folder}", f"workers={workers}", *TINY, cwd=root)
        assert result.returncode == 0, result.stderr
        assert last_json(result.stdout)["n_tasks"] == 3
    key = lambda r: (r["task"], r["final_error"], r["steps"])  # noqa: E731
    assert sorted(map(key, journal(root / "two_workers"))) == sorted(map(key, journal(root / "one_worker")))


def test_resuming_with_other_settings_is_refused(root):
    assert run("plan", "planner=initial", "hydra.run.dir=settings", "tasks=1", *TINY, cwd=root).returncode == 0
    line = error_line(run("plan", "planner=initial", "resume=settings", "success_threshold=0.5", *TINY, cwd=root))
    assert "other settings: success_threshold=0.66 (now 0.5)" in line and "new run dir" in line


@pytest.mark.parametrize("overrides,message", [
    (("planner=surprise", "planner.checkpoint=missing.ckpt"), "checkpoint missing.ckpt does not exist"),
    (("success_threshold=0",), "success_threshold=0 must be a positive number"),
    (("planner.servo_observe=rgb",), "planner.servo_observe='rgb' must be one of state, pixels"),
    (("tasks=0",), "tasks=0 plays nothing"),
    (("tasks=[2,999]",), "no task with index [999]"),
    (("pictures=-1",), "pictures=-1 must be an integer n >= 0"),
    (("pictures=[a]",), "or a list of task indices"),
    (("outcome_pictures=yes",), "outcome_pictures='yes' must be true or false"),
    (("data_dir=elsewhere",), "splits={planning: 240}"),
])
def test_bad_inputs_give_one_error_line(root, overrides, message):
    assert message in error_line(run("plan", *overrides, "hydra.run.dir=bad", cwd=root))
