"""A non-editable install works without the source tree: the configs (conf/ at the top level) travel
inside the package as keyin.conf.

The wheel is built from a copy of the package and its project files (so the checkout stays
clean) and unpacked into a folder of its own, which is all a
``pip install`` of it does for a pure-Python package; the dependencies come from this
interpreter's environment. Both commands then run from an empty folder in one subprocess.
"""

import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

COMMANDS = """
import json, sys
import keyin
print(json.dumps({"keyin": keyin.__file__}))
from keyin.cli import eval, generate
for module, argv in ((generate, ["dataset=brownian", "splits={test: 50}", "progress=false"]),
                     (eval, ["model=random", "dataset=brownian", "progress=false"])):
    sys.argv = ["keyin", *argv]
    try:
        module.main()
    except SystemExit as exit_:
        if exit_.code:
            raise
"""


def test_an_unpacked_wheel_finds_its_configs_from_an_empty_folder(tmp_path):
    source = tmp_path / "source"
    for folder in ("keyin", "conf"):
        shutil.copytree(ROOT / folder, source / folder, ignore=shutil.ignore_patterns("__pycache__"))
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, source / name)
    built = subprocess.run(
        [sys.executable, "-m", "pip", "wheel", "--no-deps", "--no-build-isolation", "-q", "-w", tmp_path / "wheel", source],
        capture_output=True, text=True,
    )
    assert built.returncode == 0, built.stderr
    (wheel,) = (tmp_path / "wheel").glob("keyin-*.whl")
    site = tmp_path / "site"
    zipfile.ZipFile(wheel).extractall(site)
    assert (site / "keyin" / "conf" / "train.yaml").is_file() and (site / "keyin" / "conf" / "model" / "keyin.yaml").is_file()
    empty = tmp_path / "elsewhere"
    empty.mkdir()
    env = dict(os.environ, PYTHONPATH=str(site))
    done = subprocess.run([sys.executable, "-c", COMMANDS], cwd=empty, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    lines = done.stdout.strip().splitlines()
    assert Path(json.loads(lines[0])["keyin"]).is_relative_to(site)  # not the source tree
    metrics = json.loads(lines[-1])
    assert metrics["method"] == "random" and metrics["n_sequences"] == 50
    assert (empty / "data" / "brownian" / "manifest.json").is_file()


def test_every_package_of_the_tree_is_listed_for_the_wheel():
    """pyproject.toml lists keyin's packages by hand (keyin.conf lives in conf/, where no search of
    keyin/ finds it): each folder with an __init__.py, and conf/, must be there."""
    tomllib = pytest.importorskip("tomllib")  # Python >= 3.11
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    found = {".".join(path.parent.relative_to(ROOT).parts) for path in (ROOT / "keyin").rglob("__init__.py")}
    assert listed == found | {"keyin.conf"}
