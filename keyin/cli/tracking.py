"""Experiment trackers at the edge of a job: wandb run names, sweep groups, online/offline, finish.

The resolvers are used by ``conf/logger/wandb.yaml``:

* ``${keyin.job_label:${name},${hydra:job.override_dirname}}``: the run's name, with the job's
  overrides in a sweep (``train_keyin_brownian[model=keyin,seed=1]``);
* ``${keyin.sweep_group:${hydra:mode},${hydra:sweep.dir}}``: all jobs of one sweep in one wandb
  group (the sweep dir), no group for a single run;
* ``${keyin.wandb_offline:}``: offline unless this machine is logged in to wandb.
"""

from __future__ import annotations

import contextlib
import netrc
import os
from pathlib import Path
from typing import Any, Iterator

from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf


def job_label(name: str, overrides: str | None) -> str:
    """``name[overrides]`` in a sweep job, ``name`` when the job has no overrides."""
    return f"{name}[{overrides}]" if overrides else name


def sweep_group(mode: Any, sweep_dir: str) -> str | None:
    """The sweep dir for the jobs of a multirun, None for a single run."""
    return str(sweep_dir) if str(mode).endswith("MULTIRUN") else None


def wandb_logged_in() -> bool:
    """True if wandb has an API key here: ``WANDB_API_KEY`` or the netrc entry ``wandb login`` writes."""
    if os.environ.get("WANDB_API_KEY"):
        return True
    path = Path(os.environ.get("NETRC", Path.home() / ".netrc"))
    try:
        hosts = netrc.netrc(path).hosts
    except (OSError, netrc.NetrcParseError):
        return False
    return any("wandb" in host for host in hosts)


for _name, _resolver in {
    "keyin.job_label": job_label,
    "keyin.sweep_group": sweep_group,
    "keyin.wandb_offline": lambda: not wandb_logged_in(),
}.items():
    OmegaConf.register_new_resolver(_name, _resolver, replace=True)


@contextlib.contextmanager
def job_logger(config: DictConfig | None) -> Iterator[Any]:
    """The job's Lightning logger (False for ``logger=none``); a wandb run it started is finished on
    exit (exit code 1 if the job raised), so the next job of a sweep in this process gets its own
    run instead of Lightning reusing ``wandb.run``."""
    from lightning.pytorch.loggers import WandbLogger

    logger = instantiate(config) if config else False
    failed = True
    try:
        yield logger
        failed = False
    finally:
        if isinstance(logger, WandbLogger) and logger._experiment is not None:
            logger.experiment.finish(exit_code=1 if failed else 0)
