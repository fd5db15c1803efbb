"""keyin-reproduce: a table from nothing (data, jobs, their small files, the report) in one command."""

import json

from keyin.cli.app import help_without_choice
from tests.cli.runner import run

TINY_TABLE = (
    "table=brownian_table1",
    "table.data=[{dataset: brownian, splits: {test: 12}}]",
    'table.sweeps=[{program: train, overrides: ["experiment=brownian_table1","model=random,constant","seed=0",'
    '"scale=smoke","scale.eval_clips=12"]}]',
    "out=results",
)


def test_one_command_writes_every_jobs_small_files_and_the_report(tmp_path):
    result = run("reproduce", *TINY_TABLE, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    jobs = tmp_path / "results" / "jobs"
    assert sorted(path.name for path in jobs.iterdir()) == ["constant_seed0", "random_seed0"]
    for job in jobs.iterdir():
        metrics = json.loads((job / "metrics.json").read_text())
        assert metrics["method"] == job.name.removesuffix("_seed0") and metrics["n_sequences"] == 12
        assert metrics["train_seconds"] >= 0 and metrics["score_seconds"] > 0
        assert "model:" in (job / "config.yaml").read_text()  # the job's composed config
        assert json.loads((job / "checkpoints.json").read_text()) == {}  # untrained rows have no checkpoint
    table = (tmp_path / "results" / "table1.md").read_text()
    assert "| brownian | random |" in table and "| brownian | constant |" in table
    # the report is rebuilt from the copied files alone, after the run folders are gone
    (tmp_path / "runs").rename(tmp_path / "gone")
    again = run("reproduce", *TINY_TABLE, "steps=[report]", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert (tmp_path / "results" / "table1.md").read_text().split("\n")[3:] == table.split("\n")[3:]
    assert (tmp_path / "results" / "examples_brownian.png").is_file()  # from the copied config.yaml


def test_a_dry_run_prints_the_commands_and_runs_none(tmp_path):
    result = run("reproduce", *TINY_TABLE, "dry_run=true", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "+ python -m keyin.cli.generate dataset=brownian 'splits={test: 12}' data_dir=data" in result.stdout
    assert "+ python -m keyin.cli.train -m experiment=brownian_table1 model=random,constant seed=0" in result.stdout
    assert not (tmp_path / "data").exists() and not (tmp_path / "results").exists()


def test_a_sweep_whose_files_exist_is_skipped_and_an_export_runs_the_pretrained_command(tmp_path):
    from omegaconf import OmegaConf

    from keyin.cli.reproduce import commands

    made = tmp_path / "made.ckpt"
    made.write_bytes(b"weights")
    sweeps = [
        {"program": "train", "overrides": ["model=jumpy"], "creates": [str(made)]},  # made already: skipped
        {"program": "train", "overrides": ["model=static"], "creates": [str(made), str(tmp_path / "missing.ckpt")]},
        {"program": "export", "overrides": ["runs/a/checkpoints/keyframes/last.ckpt", "--folder", "models"]},
    ]
    cfg = OmegaConf.create({"steps": ["jobs"], "data_dir": "data", "table": {"data": [], "sweeps": sweeps}})
    assert commands(cfg) == [
        ["keyin.cli.train", "-m", "model=static", "data_dir=data"],
        ["keyin.cli.pretrained", "export", "runs/a/checkpoints/keyframes/last.ckpt", "--folder", "models"],
    ]


def test_an_unknown_step_or_program_and_a_missing_sweep_folder_name_the_fix(tmp_path):
    bad = run("reproduce", "table=brownian_table1", "steps=[data,train]", cwd=tmp_path)
    assert bad.returncode == 2 and "['train'] are not steps; use any of ['data', 'jobs', 'collect', 'report']" in bad.stderr
    program = run("reproduce", "table=brownian_table1", "table.sweeps.0.program=fit", cwd=tmp_path)
    assert program.returncode == 2 and "table.sweeps[0].program='fit' must be one of ['eval', 'export', 'plan', 'train']" in program.stderr
    missing = run("reproduce", "table=brownian_table1", "steps=[collect]", cwd=tmp_path)
    assert missing.returncode == 2 and "does not exist: run the jobs first (steps=[jobs])" in missing.stderr


def test_collect_hashes_the_checkpoints_a_job_wrote_and_the_ones_its_config_reads(tmp_path):
    from keyin.cli.reproduce import collect
    from keyin.io import sha256_of
    from keyin.pretrained import registry

    model = tmp_path / "model.ckpt"
    model.write_bytes(b"weights")
    (tmp_path / "named.ckpt").write_bytes(b"named weights")
    job = tmp_path / "sweep" / "keyin_seed0"
    (job / ".hydra").mkdir(parents=True)
    (job / "checkpoints" / "stage").mkdir(parents=True)
    (job / "checkpoints" / "stage" / "last.ckpt").write_bytes(b"own")
    (job / ".hydra" / "config.yaml").write_text(
        f"planner:\n  checkpoint: {model}\n  other: missing.ckpt\n  shipped: pretrained:pushing\n  gone: pretrained:nothing\n"
        f"  name: named\n  by_name: {tmp_path}/${{planner.name}}.ckpt\n  runtime: ${{hydra:runtime.cwd}}/x.ckpt\n"
        f"  listed: ['${{planner.checkpoint}}']\n"
    )
    (job / "metrics.json").write_text('{"method": "keyin"}')
    (tmp_path / "sweep" / "empty").mkdir()
    assert collect(tmp_path / "sweep", tmp_path / "jobs") == ["keyin_seed0"]
    hashes = json.loads((tmp_path / "jobs" / "keyin_seed0" / "checkpoints.json").read_text())
    assert hashes == {"checkpoints/stage/last.ckpt": sha256_of(job / "checkpoints" / "stage" / "last.ckpt"), str(model): sha256_of(model),
                      "pretrained:pushing": registry()["pushing"]["sha256"],  # a shipped model by its name
                      str(tmp_path / "named.ckpt"): sha256_of(tmp_path / "named.ckpt")}  # as its interpolation resolves
    assert (tmp_path / "jobs" / "keyin_seed0" / "config.yaml").read_text().startswith("planner:")


def test_collect_copies_a_planners_outcome_pictures_and_no_other_picture(tmp_path):
    from keyin.cli.reproduce import collect

    job = tmp_path / "sweep" / "keyin_seed0"
    (job / "pictures").mkdir(parents=True)
    (job / "metrics.json").write_text('{"planner": "keyin"}')
    (job / "pictures" / "outcome_not_crossed_task007.png").write_bytes(b"\x89PNG not crossed")
    (job / "pictures" / "outcome_not_crossed_task007.gif").write_bytes(b"GIF89a")
    (job / "pictures" / "task000.png").write_bytes(b"\x89PNG first task")
    assert collect(tmp_path / "sweep", tmp_path / "jobs") == ["keyin_seed0"]
    copied = tmp_path / "jobs" / "keyin_seed0" / "pictures"
    assert sorted(path.name for path in copied.iterdir()) == ["outcome_not_crossed_task007.png"]
    assert (copied / "outcome_not_crossed_task007.png").read_bytes() == b"\x89PNG not crossed"


def test_a_sweep_puts_the_shared_lists_it_names_before_its_own_overrides_and_an_unknown_name_is_refused():
    import pytest
    from omegaconf import OmegaConf

    from keyin.cli.reproduce import check_table, sweep_overrides
    from keyin.errors import ConfigError

    table = OmegaConf.create({
        "shared": {"stage2": ["model=keyin_paper", "stage=keyframes"], "shipped": ["interpolator_ckpt=pretrained:brownian"]},
        "sweeps": [{"program": "train", "share": ["stage2", "shipped"], "overrides": ["seed=1"]},
                   {"program": "train", "overrides": ["seed=2"]}],
    })
    assert sweep_overrides(table, table.sweeps[0]) == [
        "model=keyin_paper", "stage=keyframes", "interpolator_ckpt=pretrained:brownian", "seed=1"]
    assert sweep_overrides(table, table.sweeps[1]) == ["seed=2"]
    table.sweeps[1].share = ["stage_2"]
    with pytest.raises(ConfigError, match=r"table.sweeps\[1\].share names \['stage_2'\], which table.shared does not hold"):
        check_table(OmegaConf.create({"steps": ["jobs"], "table": table}))


def test_help_before_the_table_names_the_tables_and_how_to_see_the_help(tmp_path):
    result = run("reproduce", "--help", cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "table=<option> (one of: brownian_table1," in result.stdout and "table=<option> --help" in result.stdout
    bare = run("reproduce", cwd=tmp_path)  # no help asked: the missing table is an error
    assert bare.returncode == 2 and "You must specify 'table'" in bare.stderr and not bare.stdout


def test_help_without_choice_reads_only_a_missing_choice_with_help_asked():
    missing = "You must specify 'table', e.g, table=<OPTION>; Available options: a, b"
    assert help_without_choice(missing, "keyin-x", ["-h"]) == (
        "keyin-x composes its config from table=<option> (one of: a, b); its help shows that config: "
        "keyin-x table=<option> --help")
    assert help_without_choice(missing, "keyin-x", ["seed=1"]) is None
    assert help_without_choice("Could not override 'foo'", "keyin-x", ["--help"]) is None
