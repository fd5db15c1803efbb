"""Sweeps through Hydra's launcher plugins: joblib (local processes) and submitit's local executor
(the SLURM code path on this machine). Untrained baselines keep each job to a few seconds.

The sweeps run as a real ``keyin-train`` process, not in-process like the other CLI tests: the
launchers set up logging handlers on the streams they find, and in-process those are pytest's
redirected ones, closed once the command returns (a later log line then kills the test session).
"""

import json

import pytest

from tests.cli.runner import run, run_process

pytest.importorskip("hydra_plugins.hydra_joblib_launcher")
pytest.importorskip("hydra_plugins.hydra_submitit_launcher")


@pytest.fixture(scope="module")
def test_set(tmp_path_factory):
    root = tmp_path_factory.mktemp("launchers")
    assert run("generate", "splits={test: 6}", "progress=false", cwd=root).returncode == 0
    return root


@pytest.mark.parametrize(("launcher", "seeds"), [
    (("hydra/launcher=joblib", "hydra.launcher.n_jobs=2"), (0, 1)),
    (("hydra/launcher=local",), (0,)),  # submitit starts a process per job: two jobs show it, each costs an import of torch
], ids=["joblib", "submitit-local"])
def test_a_sweep_runs_every_job_through_the_launcher(test_set, launcher, seeds):
    sweep = f"sweep_{launcher[0].split('=')[1]}"
    result = run_process("train", "-m", "model=random,constant", f"seed={','.join(map(str, seeds))}", *launcher,
                         f"hydra.sweep.dir={sweep}", cwd=test_set)
    assert result.returncode == 0, result.stderr[-3000:]
    jobs = sorted((test_set / sweep).glob("*/metrics.json"))
    rows = {(m["method"], m["seed"]) for m in (json.loads(path.read_text()) for path in jobs)}
    assert len(jobs) == 2 * len(seeds) and rows == {(method, seed) for method in ("random", "constant") for seed in seeds}
