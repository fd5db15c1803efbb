"""The checkpoints committed beside the result tables live in models/, never under docs/, and
models/manifest.json names each of them with its SHA-256, its size and the commands that made it."""

import json
import shutil
import subprocess
from pathlib import Path

import pytest
import yaml

from keyin.io import sha256_of

ROOT = Path(__file__).resolve().parents[1]
MANIFEST = ROOT / "models" / "manifest.json"


def manifest_entries() -> list[dict]:
    return json.loads(MANIFEST.read_text(encoding="utf-8"))["models"]


def test_no_checkpoint_lies_under_docs():
    found = sorted(str(path.relative_to(ROOT)) for path in (ROOT / "docs").rglob("*.ckpt"))
    assert not found, "checkpoints belong in models/ (with a models/manifest.json entry), not docs/: " + ", ".join(found)


@pytest.mark.parametrize("entry", manifest_entries(), ids=lambda entry: entry["path"])
def test_every_manifest_entry_is_its_file(entry):
    path = ROOT / entry["path"]
    assert path.is_file(), f"models/manifest.json names {entry['path']}, which does not exist"
    assert path.stat().st_size == entry["bytes"], f"{entry['path']} is {path.stat().st_size} bytes, the manifest says {entry['bytes']}"
    assert sha256_of(path) == entry["sha256"], f"{entry['path']}'s SHA-256 is not the manifest's"
    assert entry["command"] and entry["export"], f"{entry['path']}: the manifest names no command that made it"


def test_the_manifest_lists_every_committed_checkpoint_once():
    listed = [entry["path"] for entry in manifest_entries()]
    assert len(listed) == len(set(listed)), "models/manifest.json lists a checkpoint twice"
    on_disk = sorted(str(path.relative_to(ROOT)) for path in (ROOT / "models").rglob("*.ckpt"))
    assert sorted(listed) == on_disk, "models/ and models/manifest.json disagree"


def test_the_manifest_agrees_with_each_folders_model_cards():
    for entry in manifest_entries():
        path = ROOT / entry["path"]
        cards = {card["file"]: card for card in json.loads((path.parent / "models.json").read_text()).values()}
        card = cards[path.name]
        assert (card["sha256"], card["bytes"], card["command"]) == (entry["sha256"], entry["bytes"], entry["command"]), entry["path"]


def test_the_files_a_table_creates_are_in_the_manifest():
    listed = {entry["path"] for entry in manifest_entries()}
    for table in sorted((ROOT / "conf" / "table").glob("*.yaml")):
        for sweep in yaml.safe_load(table.read_text())["sweeps"]:
            for created in sweep.get("creates") or []:
                if created.startswith("models/"):
                    assert created in listed, f"{table.name} creates {created}, which models/manifest.json does not list"


@pytest.mark.skipif(shutil.which("git") is None or not (ROOT / ".git").exists(), reason="not a git checkout")
def test_git_does_not_ignore_the_committed_checkpoints():
    paths = [entry["path"] for entry in manifest_entries()]
    ignored = subprocess.run(["git", "check-ignore", "--no-index", *paths], cwd=ROOT, capture_output=True, text=True).stdout.split()
    assert not ignored, ".gitignore ignores " + ", ".join(ignored)
