"""kill -9 mid-run, then the same command again: nothing finished is redone, nothing partial is left.

The first run is a real process (``tests/cli/held.py``) held at a chosen point, e.g. with a shard
written under its temporary name but not yet renamed, and killed there with SIGKILL.
"""

import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Callable

import numpy as np
import pytest
import torch

from keyin.data.brownian import BrownianGenerator
from keyin.data.generate import generate_dataset
from keyin.data.hdf5 import load_arrays, split_files
from keyin.io import TEMPORARY_TAG
from keyin.lit.checkpoints import load_checkpoint
from tests.cli.runner import last_json, run

REPO = Path(__file__).resolve().parents[2]
GENERATE = ("generate", "splits={test: 9}", "shard_size=3", "progress=false", "data_dir=data")
TRAIN = ("train", "scale=smoke", "stage=interpolator", "scale.stage1_steps=6", "scale.checkpoint_every=2",
         "logger=none", "num_workers=0", "trainer.enable_progress_bar=false", "hydra.run.dir=run")


def kill_when(point: str, command: tuple[str, ...], cwd: Path, ready: Callable[[int], bool], timeout: float = 300) -> int:
    """Run ``command`` held at ``point`` in a new process, SIGKILL it once ``ready(its pid)``; its exit code."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(REPO), os.environ.get("PYTHONPATH")])))
    with tempfile.TemporaryFile("w+") as log:
        child = subprocess.Popen([sys.executable, "-m", "tests.cli.held", point, *command], cwd=cwd, env=env,
                                 stdout=log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + timeout
        try:
            while not ready(child.pid):
                if child.poll() is not None:
                    log.seek(0)
                    pytest.fail(f"the command ended before the kill point: {log.read()[-2000:]}")
                assert time.monotonic() < deadline, "the kill point was never reached"
                time.sleep(0.01)
        finally:
            child.send_signal(signal.SIGKILL)
            child.wait()
    return child.returncode


@pytest.mark.parametrize("point,partial,recovered", [
    pytest.param("rename:test-00001.h5", ".test-00001.h5", 0, id="mid-shard"),
    pytest.param("rename:manifest.json", ".manifest.json", 1, id="shard-done-manifest-not"),
])
def test_generate_killed_mid_run_redoes_no_finished_shard_and_leaves_no_partial_file(tmp_path, point, partial, recovered):
    folder = tmp_path / "data" / "brownian"
    partials = lambda: list(folder.glob(f"{partial}{TEMPORARY_TAG}*"))  # noqa: E731
    assert kill_when(point, GENERATE, tmp_path, lambda pid: bool(partials())) == -9
    assert len(partials()) == 1 and (folder / "test-00000.h5").is_file()
    finished = (folder / "test-00000.h5").stat().st_mtime_ns

    result = run(*GENERATE, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    stats = last_json(result.stdout)
    assert (stats["shards_skipped"], stats["shards_recovered"], stats["clips"]) == (1, recovered, 6)
    assert stats["stale_temporaries_removed"] == 1
    assert (folder / "test-00000.h5").stat().st_mtime_ns == finished
    assert sorted(p.name for p in folder.iterdir()) == ["manifest.json"] + [f"test-0000{i}.h5" for i in range(3)]
    generate_dataset(BrownianGenerator(), tmp_path / "clean", "brownian", {"test": 9}, 3, 0, progress=False)
    for resumed, clean in zip(split_files(folder, "test"), split_files(tmp_path / "clean", "test"), strict=True):
        np.testing.assert_array_equal(load_arrays(resumed)["frames"], load_arrays(clean)["frames"])


def children_of(pid: int) -> set[int]:
    """The ids of a process's children (Linux /proc)."""
    children = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rpartition(")")[2].split()
        except OSError:  # the process ended meanwhile
            continue
        if int(fields[1]) == pid:
            children.add(int(stat.parent.name))
    return children


def alive(pid: int) -> bool:
    stat = Path(f"/proc/{pid}/stat")
    try:
        return stat.read_text().rpartition(")")[2].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.skipif(not Path("/proc/self/stat").is_file(), reason="reads processes from Linux /proc")
def test_generate_workers_end_soon_after_their_parent_is_killed(tmp_path):
    folder, workers = tmp_path / "data" / "brownian", set()

    def first_shard_done(pid: int) -> bool:
        if not (folder / "test-00000.h5").is_file():
            return False
        workers.update(children_of(pid))  # the pool's workers (and its resource tracker)
        return True

    command = ("generate", "splits={test: 3000}", "shard_size=100", "workers=2", "progress=false", "data_dir=data")
    assert kill_when("none", command, tmp_path, first_shard_done) == -9
    assert len(workers) >= 2
    deadline = time.monotonic() + 15
    while any(alive(pid) for pid in workers) and time.monotonic() < deadline:
        time.sleep(0.1)
    orphans = [pid for pid in workers if alive(pid)]
    for pid in orphans:  # do not leave them behind when the test fails
        os.kill(pid, signal.SIGKILL)
    assert not orphans, "orphaned workers kept running"


def adam_steps(checkpoint: dict) -> set[float]:
    return {float(state["step"]) for state in checkpoint["optimizer_states"][0]["state"].values()}


@pytest.mark.slow  # about 30 s: the killed process imports torch and Lightning itself
def test_train_killed_after_a_checkpoint_resumes_its_step_count_and_optimizer_state(tmp_path):
    last = tmp_path / "run" / "checkpoints" / "interpolator" / "last.ckpt"
    assert kill_when("checkpoint", TRAIN, tmp_path, lambda pid: last.is_file()) == -9
    killed = load_checkpoint(last)
    assert killed["global_step"] == 2 and adam_steps(killed) == {2.0}
    (loader,) = killed["loops"]["fit_loop"]["state_dict"]["combined_loader"]
    assert loader["_num_yielded"] == 2  # the train loader's place in the epoch is kept: resuming continues it

    # Resumed to the step it was killed at (no further step), the state saved again is the same.
    shutil.copytree(tmp_path / "run", tmp_path / "copy")
    same = run(*TRAIN[:-1], "scale.stage1_steps=2", "hydra.run.dir=copy", cwd=tmp_path)
    assert same.returncode == 0, same.stderr
    restored = load_checkpoint(tmp_path / "copy" / "checkpoints" / "interpolator" / "last.ckpt")
    assert restored["global_step"] == 2
    for name, value in killed["state_dict"].items():
        torch.testing.assert_close(restored["state_dict"][name], value, rtol=0, atol=0)
    for key, state in killed["optimizer_states"][0]["state"].items():
        for name, value in state.items():
            torch.testing.assert_close(restored["optimizer_states"][0]["state"][key][name], value, rtol=0, atol=0)

    # The same command again finishes the run: 4 more steps, Adam's step count continued, not reset.
    result = run(*TRAIN, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    finished = load_checkpoint(last)
    assert finished["global_step"] == 6 and adam_steps(finished) == {6.0}
    assert sorted(p.name for p in last.parent.iterdir()) == ["last.ckpt"]


PLAN = ("plan", "planner=random", "tasks=3", "planner.max_timesteps=3", "progress=false", "hydra.run.dir=plan")


@pytest.mark.slow  # about 40 s: generates 3 planning tasks and imports MuJoCo twice
def test_plan_killed_mid_line_redoes_no_finished_task_and_keeps_no_partial_line(tmp_path):
    generated = run("generate", "dataset=pushing", "splits={planning: 3}", "progress=false", cwd=tmp_path)
    assert generated.returncode == 0, generated.stderr
    journal = tmp_path / "plan" / "tasks.jsonl"

    def half_written(pid: int) -> bool:
        return journal.is_file() and journal.read_text().count("\n") == 1 and not journal.read_text().endswith("\n")

    assert kill_when("journal:1", PLAN, tmp_path, half_written) == -9
    finished = journal.read_text().partition("\n")[0]

    result = run(*PLAN, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    metrics = last_json(result.stdout)
    assert (metrics["skipped"], metrics["played"], metrics["partial_lines_dropped"]) == (1, 2, 1)
    lines = journal.read_text().splitlines()
    assert lines[0] == finished and [json.loads(line)["task"] for line in lines] == [0, 1, 2]
