"""Carry a background job's resumable checkpoint from one machine to the next (issue 62).

A session's machine may be replaced before the next session, and git-ignored run folders go with it. ``save``
writes the job's ``last.ckpt`` into ``models/in_progress/`` (committed): the weights as they are, Adam's moments in
bfloat16 (torch's ``Optimizer.load_state_dict`` casts them back to the weights' float32 on resume), and lists it in
``models/manifest.json`` and the folder's ``models.json``; it also records the job in ``docs/results/keyin_paper_stated/jobs/<job>/``
(committed): its composed ``config.yaml``, its metrics so far (``stage1_metrics.csv`` or ``stage2_metrics.csv``, the rows of
every run, a resumed run's rows replacing those it repeats) and ``checkpoints.json`` (the live and the carried checkpoint's SHA-256, step and size; its
``note`` is kept). ``restore`` puts the checkpoint back where the job resumes from (its periodic saves overwriting that file:
:func:`owning_last`). ``extend`` starts a longer job from a
finished one's last checkpoint, its optimizer and step counter included, under the longer job's row name (the run goes on
where it stopped, so the row's curve is one run; the finished job keeps its folder and its test scores).

    python docs/results/keyin_paper_stated/scripts/carry.py save <jobs dir> <job>      # e.g. /work/jobs stated_seed0
    python docs/results/keyin_paper_stated/scripts/carry.py restore <jobs dir> <job>
    python docs/results/keyin_paper_stated/scripts/carry.py save <jobs dir> stated_stage2_seed1 --stage keyframes
    python docs/results/keyin_paper_stated/scripts/carry.py extend <jobs dir> stated_stage2_seed0_20k --stage keyframes \
        --from stated_stage2_seed0 --model keyin_paper_stated_10k_20k
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import os
from datetime import date
from pathlib import Path

import torch
from omegaconf import OmegaConf

from keyin.checkpoints import CONFIG_KEY
from keyin.io import atomic_write_bytes, atomic_write_text, sha256_of

ROOT = Path(__file__).resolve().parents[4]
FOLDER = ROOT / "models" / "in_progress"
MANIFEST = ROOT / "models" / "manifest.json"
STAGES = {  # stage → (the name it carries in models/in_progress/, the command that trains it)
    "interpolator": ("stage1", "sh docs/results/keyin_paper_stated/scripts/stage1.sh <seed> <jobs dir> <data dir>"),
    "keyframes": ("stage2", "sh docs/results/keyin_paper_stated/scripts/stage2.sh <seed> <steps> <jobs dir> <data dir>"),
}
EXPORT = "python docs/results/keyin_paper_stated/scripts/carry.py save <jobs dir> <job> --stage <stage>"
RECORDS = ROOT / "docs" / "results" / "keyin_paper_stated" / "jobs"


def job_checkpoint(jobs: Path, job: str, stage: str = "interpolator") -> Path:
    return jobs / job / "checkpoints" / stage / "last.ckpt"


def job_model(jobs: Path, job: str) -> str:
    """The row name the job runs under (its Hydra config's ``model.name``)."""
    return str(OmegaConf.load(jobs / job / ".hydra" / "config.yaml").model.name)


def carried(job: str, stage: str = "interpolator") -> Path:
    return FOLDER / f"{job}_{STAGES[stage][0]}_last.ckpt"


def write_checkpoint(path: Path, checkpoint: dict) -> None:
    """``torch.save`` through keyin's atomic write: ``path`` keeps its old file or gets the whole new one."""
    buffer = io.BytesIO()
    torch.save(checkpoint, buffer)
    atomic_write_bytes(path, buffer.getvalue())


def slimmed(checkpoint: dict) -> dict:
    """The checkpoint with every floating optimizer state tensor (Adam's moments) in bfloat16; weights untouched."""
    for optimizer in checkpoint.get("optimizer_states", []):
        for state in optimizer["state"].values():
            for key, value in state.items():
                if key != "step" and torch.is_tensor(value) and value.is_floating_point():
                    state[key] = value.to(torch.bfloat16)
    return checkpoint


def owning_last(checkpoint: dict, path: Path) -> dict:
    """The checkpoint with its ``save_last`` ModelCheckpoint's state pointing at ``path``, the job's own ``last.ckpt``.

    Lightning overwrites a ``last.ckpt`` only where the state it resumes says it wrote that file; a checkpoint from another
    folder (``extend``) or one saved as ``last-v1.ckpt`` would make the job's periodic saves go to a versioned file
    (``last-v1.ckpt``) that it does not resume from."""
    for key, state in checkpoint.get("callbacks", {}).items():
        if key.startswith("ModelCheckpoint") and state.get("last_model_path"):
            state["dirpath"], state["last_model_path"] = os.path.realpath(path.parent), os.path.realpath(path)
    return checkpoint


def save(jobs: Path, job: str, stage: str = "interpolator") -> Path:
    source = job_checkpoint(jobs, job, stage)
    checkpoint = torch.load(source, map_location="cpu", weights_only=False)
    target = carried(job, stage)
    FOLDER.mkdir(parents=True, exist_ok=True)
    write_checkpoint(target, slimmed(checkpoint))
    card = {
        "file": target.name, "bytes": target.stat().st_size, "sha256": sha256_of(target), "command": STAGES[stage][1],
        "source_sha256": sha256_of(source), "global_step": checkpoint["global_step"], "stage": stage,
        "model": job_model(jobs, job), "dataset": "brownian",
    }
    cards_path = FOLDER / "models.json"
    cards = json.loads(cards_path.read_text()) if cards_path.is_file() else {}
    cards[target.stem] = card
    atomic_write_text(cards_path, json.dumps(cards, indent=1, sort_keys=True) + "\n")
    manifest = json.loads(MANIFEST.read_text())
    path = str(target.relative_to(ROOT))
    entry = {key: card[key] for key in ("sha256", "bytes", "command", "source_sha256", "model", "stage", "dataset")}
    entry |= {"path": path, "export": EXPORT, "table": "docs/results/keyin_paper_stated"}
    manifest["models"] = [e for e in manifest["models"] if e["path"] != path] + [entry]
    atomic_write_text(MANIFEST, json.dumps(manifest, indent=1) + "\n")
    print(f"{source} (step {checkpoint['global_step']}) → {path}, {card['bytes']} bytes")
    record(jobs, job, stage, {"sha256": card["source_sha256"], "global_step": checkpoint["global_step"],
                              "bytes": source.stat().st_size}, {"path": path, "sha256": card["sha256"], "bytes": card["bytes"]})
    return target


def is_test_row(row: dict[str, str]) -> bool:
    """A row of the test scoring at the end of a job, which Lightning logs at step 0."""
    return all(key.startswith("test/") for key, value in row.items() if value and key not in ("epoch", "step"))


def merged_rows(runs: list[list[dict[str, str]]]) -> list[dict[str, str]]:
    """The metrics rows of a job's runs in the order they ran, each run's rows replacing the earlier rows at or after its
    first training or validation step (a resumed run repeats the steps after its checkpoint; its test row, at step 0,
    replaces only an earlier test row)."""
    rows: list[dict[str, str]] = []
    for run in (run for run in runs if run):
        steps = [int(row["step"]) for row in run if not is_test_row(row)]
        first = min(steps) if steps else float("inf")
        tested = any(is_test_row(row) for row in run)
        rows = [row for row in rows if (int(row["step"]) < first and not is_test_row(row)) or (is_test_row(row) and not tested)]
        rows += run
    return rows


def read_rows(path: Path) -> list[dict[str, str]]:
    return list(csv.DictReader(io.StringIO(path.read_text()))) if path.is_file() else []


def record(jobs: Path, job: str, stage: str, live: dict, carried_file: dict) -> None:
    """The job's config, metrics and checkpoint hashes into its committed folder (see the module's docstring)."""
    folder = RECORDS / job
    folder.mkdir(parents=True, exist_ok=True)
    atomic_write_text(folder / "config.yaml", (jobs / job / ".hydra" / "config.yaml").read_text())
    metrics = folder / f"{STAGES[stage][0]}_metrics.csv"
    versions = sorted((jobs / job / "csv").glob("version_*/metrics.csv"), key=lambda p: int(p.parent.name.split("_")[1]))
    rows = merged_rows([read_rows(metrics)] + [read_rows(path) for path in versions])
    columns = list(dict.fromkeys(key for row in rows for key in row))
    text = io.StringIO()
    writer = csv.DictWriter(text, fieldnames=columns, restval="", lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    atomic_write_text(metrics, text.getvalue())
    cards_path = folder / "checkpoints.json"
    cards = json.loads(cards_path.read_text()) if cards_path.is_file() else {}
    cards |= {f"checkpoints/{stage}/last.ckpt": live, "carried": carried_file, "date": str(date.today())}
    atomic_write_text(cards_path, json.dumps(cards, indent=1) + "\n")
    print(f"{metrics.relative_to(ROOT)}: {len(rows)} rows; {cards_path.relative_to(ROOT)} at step {live['global_step']}")


def restore(jobs: Path, job: str, stage: str = "interpolator") -> None:
    source, target = carried(job, stage), job_checkpoint(jobs, job, stage)
    if target.is_file():
        print(f"{target} exists: the job resumes from it")
        return
    if not source.is_file():
        print(f"no {source.relative_to(ROOT)}: the job starts from scratch")
        return
    target.parent.mkdir(parents=True, exist_ok=True)
    write_checkpoint(target, owning_last(torch.load(source, map_location="cpu", weights_only=False), target))
    print(f"{source.relative_to(ROOT)} → {target}")


def extend(jobs: Path, job: str, stage: str, source_job: str, model: str) -> None:
    """``job`` starts from ``source_job``'s last checkpoint, renamed to the row ``model`` it now trains as."""
    source, target = job_checkpoint(jobs, source_job, stage), job_checkpoint(jobs, job, stage)
    if target.is_file():
        print(f"{target} exists: the job resumes from it")
        return
    if not source.is_file():
        raise SystemExit(f"{source} is missing: finish {source_job} first (or restore it: carry.py restore)")
    checkpoint = torch.load(source, map_location="cpu", weights_only=False)
    checkpoint[CONFIG_KEY]["model"]["name"] = model
    target.parent.mkdir(parents=True, exist_ok=True)
    write_checkpoint(target, owning_last(checkpoint, target))
    print(f"{source} (step {checkpoint['global_step']}) → {target} as model {model}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("action", choices=("save", "restore", "extend"))
    parser.add_argument("jobs", type=Path)
    parser.add_argument("job")
    parser.add_argument("--stage", choices=tuple(STAGES), default="interpolator")
    parser.add_argument("--from", dest="source", help="extend: the finished job to go on from")
    parser.add_argument("--model", help="extend: the row name the longer job trains as")
    args = parser.parse_args()
    if args.action == "extend":
        if not (args.source and args.model):
            parser.error("extend needs --from <finished job> and --model <row name>")
        extend(args.jobs, args.job, args.stage, args.source, args.model)
    else:
        (save if args.action == "save" else restore)(args.jobs, args.job, args.stage)


if __name__ == "__main__":
    main()
