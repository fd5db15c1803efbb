"""keyin-train experiment=<name>: train the chosen model (KEYIN's two stages, or Surprise's or
TAP's one), then score its keyframes on the test split (TAP, which finds none, scores itself).
Untrained baselines (Random, Constant) are only scored, so one sweep covers every row of Table 1.

This module checks the config only; torch and Lightning are imported once a job runs
(:mod:`keyin.cli.train_job`), so ``--help``, ``--cfg job`` and a bad value answer at once.
"""

from __future__ import annotations

from omegaconf import DictConfig

from keyin.cli.app import finished_metrics, keyin_main, run_dir, user_errors
from keyin.cli.checks import check_common, check_training


@user_errors
def train(cfg: DictConfig) -> dict | None:
    check_common(cfg)
    check_training(cfg)
    folder = run_dir()
    finished = finished_metrics(folder) if cfg.skip_finished else None
    if finished is not None:
        return finished
    from keyin.cli.train_job import run_job

    return run_job(cfg, folder)


main = keyin_main("train")(train)  # the console script: Hydra, then train(cfg)


if __name__ == "__main__":
    main()
