"""keyin-reproduce table=<name>: data, every job, their small files and the report of one committed table.

The table's config (``conf/table/<name>.yaml``) names the datasets to generate, the sweeps to run
(each a ``keyin-train -m``, ``keyin-eval -m`` or ``keyin-plan -m`` call, resumable: finished jobs are skipped,
or a ``python -m keyin.cli.pretrained export`` of trained models into a committed folder; a sweep whose
``creates`` files all exist is skipped: the models a table plans with are committed) and the
folder the table's jobs are in. Each job's ``metrics.json`` (and ``tasks.jsonl``, ``predictions.json``, a
planner's one picture per outcome kind), its composed ``config.yaml`` and the SHA-256 of every checkpoint
it wrote or read (``checkpoints.json``) are copied to ``<out>/jobs/<job>/``, so the report, built from
those files by ``keyin-report``, can be rebuilt after the run folders are gone.
"""

from __future__ import annotations

import json
import shlex
import subprocess
import sys
from pathlib import Path

from omegaconf import DictConfig, ListConfig, OmegaConf
from omegaconf.errors import InterpolationResolutionError

from keyin.cli import report
from keyin.cli.app import keyin_main, user_errors
from keyin.errors import ConfigError, KeyinError
from keyin.io import atomic_write_bytes, atomic_write_text, sha256_of
from keyin.pretrained import PREFIX, is_pretrained, registry, resolve

STEPS = ("data", "jobs", "collect", "report")
PROGRAMS = {"train": "keyin.cli.train", "eval": "keyin.cli.eval", "plan": "keyin.cli.plan", "export": "keyin.cli.pretrained"}
SMALL_FILES = ("metrics.json", "predictions.json", "tasks.jsonl")  # copied as they are; the config comes from .hydra/
OUTCOME_PICTURES = "pictures/outcome_*.png"  # keyin-plan's first episode of each outcome kind


def made_already(sweep: DictConfig) -> bool:
    """Whether every file the sweep ``creates`` exists (False for a sweep that names none)."""
    created = sweep.get("creates") or []
    return bool(created) and all(Path(path).is_file() for path in created)


def sweep_overrides(table: DictConfig, sweep: DictConfig) -> list[str]:
    """A sweep's overrides: those of the table's ``shared`` lists it names in ``share`` (in order), then its own."""
    shared = table.get("shared") or {}
    return [*(override for name in sweep.get("share") or [] for override in shared[name]), *sweep.overrides]


def commands(cfg: DictConfig) -> list[list[str]]:
    """The keyin-generate and sweep calls of the chosen steps, in order, without the sweeps made already."""
    table, calls = cfg.table, []
    if "data" in cfg.steps:
        for entry in table.data:
            splits = json.dumps(OmegaConf.to_container(entry.splits)).replace('"', "")
            calls.append(["keyin.cli.generate", f"dataset={entry.dataset}", f"splits={splits}", f"data_dir={cfg.data_dir}"])
    if "jobs" in cfg.steps:
        for sweep in table.sweeps:
            if made_already(sweep):
                continue
            if sweep.program == "export":
                calls.append([PROGRAMS["export"], "export", *sweep_overrides(table, sweep)])
            else:
                calls.append([PROGRAMS[sweep.program], "-m", *sweep_overrides(table, sweep), f"data_dir={cfg.data_dir}"])
    return calls


def collect(sweep_dir: Path, jobs_dir: Path) -> list[str]:
    """Copy every job's small files from ``sweep_dir`` to ``jobs_dir/<job>/``; returns the jobs copied.

    A job is a folder with a ``metrics.json``; a folder with checkpoints only (a stage 1 shared by
    several jobs) keeps its ``checkpoints.json``, so every trained network of the table is named by hash.
    """
    copied = []
    for folder in sorted(path for path in sweep_dir.iterdir() if path.is_dir()):
        checkpoints = {str(path.relative_to(folder)): path for path in sorted(folder.glob("checkpoints/**/*.ckpt"))}
        checkpoints |= read_checkpoints(folder / ".hydra" / "config.yaml")
        if not (folder / "metrics.json").is_file() and not checkpoints:
            continue
        target = jobs_dir / folder.name
        target.mkdir(parents=True, exist_ok=True)
        for name in SMALL_FILES:
            if (folder / name).is_file():
                atomic_write_text(target / name, (folder / name).read_text())
        for picture in sorted(folder.glob(OUTCOME_PICTURES)):  # a planner's one picture per outcome kind
            (target / "pictures").mkdir(exist_ok=True)
            atomic_write_bytes(target / "pictures" / picture.name, picture.read_bytes())
        if (folder / ".hydra" / "config.yaml").is_file():
            atomic_write_text(target / "config.yaml", (folder / ".hydra" / "config.yaml").read_text())
        hashes = {name: sha256_of(path) for name, path in checkpoints.items()}
        atomic_write_text(target / "checkpoints.json", json.dumps(hashes, indent=1, sort_keys=True) + "\n")
        copied.append(folder.name)
    return copied


def read_checkpoints(config_file: Path) -> dict[str, Path]:
    """The checkpoints a job's composed config names (a planner's, a stage 1's) that exist, by the name
    the config gives them (a path, or ``pretrained:<name>`` for a model shipped with keyin) → their file.
    A value with interpolations (``models/${planner.model}_seed${seed}.ckpt``) counts as it resolves; one
    that does not resolve outside its run (``${hydra:...}``) is passed over."""
    if not config_file.is_file():
        return {}
    found: dict[str, Path] = {}

    def visit(node: object) -> None:
        if isinstance(node, (DictConfig, ListConfig)):
            for key in node.keys() if isinstance(node, DictConfig) else range(len(node)):
                try:
                    visit(node[key])
                except InterpolationResolutionError:
                    continue
        elif isinstance(node, str) and is_pretrained(node) and node[len(PREFIX):] in registry():
            found[node] = resolve(node)
        elif isinstance(node, str) and node.endswith(".ckpt") and Path(node).is_file():
            found[node] = Path(node)

    visit(OmegaConf.load(config_file))
    return dict(sorted(found.items()))


def check_table(cfg: DictConfig) -> None:
    unknown = [step for step in cfg.steps if step not in STEPS]
    if unknown:
        raise ConfigError(f"steps={list(cfg.steps)}: {unknown} are not steps; use any of {list(STEPS)}")
    shared = cfg.table.get("shared") or {}
    for index, sweep in enumerate(cfg.table.sweeps):
        if sweep.program not in PROGRAMS:
            raise ConfigError(f"table.sweeps[{index}].program={sweep.program!r} must be one of {sorted(PROGRAMS)}")
        unknown = [name for name in sweep.get("share") or [] if name not in shared]
        if unknown:
            raise ConfigError(f"table.sweeps[{index}].share names {unknown}, which table.shared does not hold; "
                              f"it holds {sorted(shared)}")


@user_errors
def reproduce(cfg: DictConfig) -> list[str]:
    check_table(cfg)
    for call in commands(cfg):
        print("+ python -m " + shlex.join(call), flush=True)
        if not cfg.dry_run and subprocess.run([sys.executable, "-m", *call]).returncode != 0:
            raise KeyinError(
                f"python -m {shlex.join(call)} failed (its output is above); fix it and run keyin-reproduce again: "
                "finished jobs are skipped"
            )
    out, sweep_dir = Path(cfg.out), Path(cfg.table.sweep_dir)
    copied: list[str] = []
    if "collect" in cfg.steps and not cfg.dry_run:
        if not sweep_dir.is_dir():
            raise ConfigError(f"table.sweep_dir={sweep_dir} does not exist: run the jobs first (steps=[jobs])")
        copied = collect(sweep_dir, out / "jobs")
        print(f"copied the small files of {len(copied)} folders to {out / 'jobs'}")
    if "report" in cfg.steps and not cfg.dry_run:
        report.main([str(out / "jobs"), "--out", str(out), *cfg.table.report])
    return copied


main = keyin_main("reproduce")(reproduce)  # the console script: Hydra, then reproduce(cfg)


if __name__ == "__main__":
    main()
