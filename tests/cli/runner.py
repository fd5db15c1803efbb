"""Run a console script's ``main()`` in this process, as the shell would, and capture its output.

A subprocess per call would re-import torch and lightning (about 30 s each on the 2-core CI
machine); in-process the imports are paid once per test session. ``main()`` still goes through
Hydra's command-line parsing, config composition, the run dir and ``sys.exit``.

Hydra's logging set-up is left out (``hydra/job_logging=none``): it closes every existing logging
handler, and absl's handler (installed when dm_control is imported by another test module) then
closes the stream it was created with — pytest's capture — once ``sys.stderr`` is redirected here.
"""

from __future__ import annotations

import contextlib
import importlib
import io
import json
import os
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path


NO_HYDRA_LOGGING = ("hydra/job_logging=none", "hydra/hydra_logging=none")


@dataclass
class Result:
    returncode: int
    stdout: str
    stderr: str


def run(module: str, *overrides: str, cwd: Path) -> Result:
    """``keyin-<module> overrides...`` run in ``cwd``; returns its exit status and output."""
    main = importlib.import_module(f"keyin.cli.{module}").main
    stdout, stderr = io.StringIO(), io.StringIO()
    previous_dir, previous_argv = os.getcwd(), sys.argv
    sys.argv = [f"keyin-{module}", *overrides, *NO_HYDRA_LOGGING]
    returncode = 0
    try:
        os.chdir(cwd)
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
            main()
    except SystemExit as exit_:
        returncode = exit_.code if isinstance(exit_.code, int) else 1
    finally:
        os.chdir(previous_dir)
        sys.argv = previous_argv
    return Result(returncode, stdout.getvalue(), stderr.getvalue())


def run_process(module: str, *overrides: str, cwd: Path, timeout: float = 600) -> Result:
    """``keyin-<module> overrides...`` as its own process (the console script next to this Python),
    for commands whose launchers or loggers wrap the process's streams."""
    script = Path(sys.executable).parent / f"keyin-{module}"
    done = subprocess.run([str(script), *overrides], cwd=cwd, capture_output=True, text=True, timeout=timeout)
    return Result(done.returncode, done.stdout, done.stderr)


def last_json(stdout: str) -> dict:
    """The JSON object every entry point prints as its last line."""
    return json.loads(stdout.strip().splitlines()[-1])


def error_line(result: Result) -> str:
    """The one ``error:`` line of a command that stopped on bad input (exit status 2, no traceback)."""
    lines = [line for line in result.stderr.splitlines() if line.startswith("error:")]
    assert result.returncode == 2, result.stderr[-2000:]
    assert len(lines) == 1 and "Traceback" not in result.stderr, result.stderr[-2000:]
    return lines[0]


def train_on_few_pushing_demos(root: Path, *train: str) -> dict:
    """Generate 4 pushing clips per split in ``root``, run ``keyin-train train...`` there and return
    its metrics (the one-stage models' end-to-end fixtures)."""
    generated = run("generate", "dataset=pushing", "splits={train: 4, val: 4, test: 4}", "progress=false", cwd=root)
    assert generated.returncode == 0, generated.stderr
    result = run("train", *train, cwd=root)
    assert result.returncode == 0, result.stderr[-3000:]
    return last_json(result.stdout)
