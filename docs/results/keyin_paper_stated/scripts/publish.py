"""Put the stated row's finished stage-2 jobs into the Brownian Table 1 report (issue 62).

Each finished job (``<jobs>/stated_stage2_seed<N>``, or ``stated_stage2_seed<N>_<steps/1000>k`` for a longer budget as
``stage2.sh`` names it; its ``metrics.json`` written by the test scoring at the end of ``stage2.sh``) is copied as ``keyin.cli.reproduce.collect`` copies a sweep's jobs, named by its row and seed
(``<model.name>_seed<N>``: its config, metrics, predictions and checkpoint hashes), with the stage 1 the seeds share
(``stated_seed0``, its config and checkpoint hash); then the report is rebuilt from every committed job.

    python docs/results/keyin_paper_stated/scripts/publish.py /work/jobs 0 1 2
    python docs/results/keyin_paper_stated/scripts/publish.py /work/jobs 0 --steps 20000   # item 4's row, 10k + 20k
"""

from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
from pathlib import Path

from omegaconf import OmegaConf

from keyin.cli.reproduce import collect

ROOT = Path(__file__).resolve().parents[4]
TABLE = ROOT / "docs" / "results" / "brownian_table1"
STAGE1 = "stated_seed0"
ROW_STEPS = 5000  # the 3-seed row's stage-2 budget; a longer one is a job of its own (stage2.sh)


def stage2_job(seed: int, steps: int) -> str:
    """The run folder ``stage2.sh <seed> <steps>`` trains in."""
    return f"stated_stage2_seed{seed}" + ("" if steps == ROW_STEPS else f"_{steps // 1000}k")


def job_names(jobs: Path, seeds: list[int], steps: int = ROW_STEPS) -> dict[str, Path]:
    """Table job name → the finished run folder of each seed (its ``steps``-step job) and of the shared stage 1; a seed
    not finished is an error that names what is missing and how to finish it."""
    named = {"keyin_paper_stated_stage1_seed0": jobs / STAGE1}
    for seed in seeds:
        folder = jobs / stage2_job(seed, steps)
        if not (folder / "metrics.json").is_file():
            raise SystemExit(f"{folder}/metrics.json is missing: seed {seed} has not finished (stage2.sh scores the test "
                             "clips at its last step); resume it with docs/results/keyin_paper_stated/scripts/restart.sh")
        named[f"{OmegaConf.load(folder / '.hydra' / 'config.yaml').model.name}_seed{seed}"] = folder
    return named


def publish(jobs: Path, seeds: list[int], table: Path = TABLE, steps: int = ROW_STEPS) -> list[str]:
    """Copy the jobs into ``table/jobs/`` under their table names; returns the names copied."""
    with tempfile.TemporaryDirectory() as staging:
        for name, folder in job_names(jobs, seeds, steps).items():
            (Path(staging) / name).symlink_to(folder.resolve(), target_is_directory=True)
        return collect(Path(staging), table / "jobs")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("jobs", type=Path)
    parser.add_argument("seeds", type=int, nargs="+")
    parser.add_argument("--steps", type=int, default=ROW_STEPS, help="the jobs' stage-2 budget, as given to stage2.sh")
    parser.add_argument("--no-report", action="store_true", help="copy the jobs only")
    args = parser.parse_args()
    print("copied:", ", ".join(publish(args.jobs, args.seeds, steps=args.steps)))
    if not args.no_report:
        report = Path(sys.executable).with_name("keyin-report")  # paths from the root: the report names its command
        table = TABLE.relative_to(ROOT)
        subprocess.run([str(report), str(table / "jobs"), "--out", str(table)], check=True, cwd=ROOT)


if __name__ == "__main__":
    main()
