"""tasks.jsonl and plan.json: whole lines only, a killed writer's partial line dropped, settings kept."""

import json

import pytest

from keyin.errors import ConfigError, DatasetFormatError
from keyin.io import append_json_line
from keyin.planning.journal import claim_run_dir, read_journal


def test_records_round_trip_and_a_partial_last_line_is_dropped_from_the_file(tmp_path):
    path = tmp_path / "tasks.jsonl"
    assert read_journal(path) == ([], False)
    append_json_line(path, {"task": 0, "final_error": 0.5})
    with open(path, "a") as handle:
        handle.write('{"task": 1, "fin')  # killed mid-write
    assert read_journal(path) == ([{"task": 0, "final_error": 0.5}], True)
    assert path.read_text() == '{"final_error": 0.5, "task": 0}\n'
    append_json_line(path, {"task": 1})
    assert read_journal(path) == ([{"task": 0, "final_error": 0.5}, {"task": 1}], False)
    path.write_text('{"task": 0}\nnot json\n')
    with pytest.raises(DatasetFormatError, match="line 2 is not a JSON object"):
        read_journal(path)


def test_a_run_dir_keeps_its_settings(tmp_path):
    settings = {"planner": {"name": "random", "max_timesteps": 3}, "seed": 0}
    claim_run_dir(tmp_path, settings)
    claim_run_dir(tmp_path, settings)
    assert json.loads((tmp_path / "plan.json").read_text()) == settings
    with pytest.raises(ConfigError, match=r"planner.max_timesteps=3 \(now 4\), seed=0 \(now None\)"):
        claim_run_dir(tmp_path, {"planner": {"name": "random", "max_timesteps": 4}})


def test_a_run_dir_claimed_before_a_setting_existed_resumes_at_its_old_value(tmp_path):
    (tmp_path / "plan.json").write_text('{"planner": {"name": "keyin"}, "seed": 0}')  # no servo_observe, no model_seed
    claim_run_dir(tmp_path, {"planner": {"name": "keyin", "servo_observe": "state", "model_seed": 0}, "seed": 0})
    with pytest.raises(ConfigError, match="planner.servo_observe='state' \\(now 'pixels'\\)"):
        claim_run_dir(tmp_path, {"planner": {"name": "keyin", "servo_observe": "pixels", "model_seed": 0}, "seed": 0})
