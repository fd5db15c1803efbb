"""How a job is named: its folder in a sweep and its run in the trackers.

The resolvers are used by ``conf/hydra_dirs.yaml`` and the logger configs:

* ``${keyin.job_dir:${hydra.job.override_dirname},${hydra.job.num}}``: a sweep job's folder, named by
  its overrides (``model=jumpy,seed=1``; tracker and display keys left out by
  ``hydra.job.config.override_dirname.exclude_keys``), the job number when it has none;
* ``${keyin.job_label:<method>,<dataset>,<seed>,${hydra:job.override_dirname}}``: the run's name in
  TensorBoard and wandb, ``jumpy-brownian-seed1[model=jumpy,seed=1]``;
* ``${keyin.tracking_dir:${hydra:mode},${hydra:sweep.dir},${hydra:runtime.output_dir}}``: where the
  TensorBoard runs of a job go: the sweep dir for every job of a sweep, else the run dir;
* ``${keyin.wandb_offline:}``: offline unless this machine is logged in to wandb.

No Lightning here: every entry point imports it, and keyin-discover starts without Lightning.
"""

from __future__ import annotations

import hashlib
import netrc
import os
import re
from pathlib import Path
from typing import Any

from omegaconf import OmegaConf

UNSAFE = re.compile(r"[^A-Za-z0-9._,=+@\[\]-]")  # what a file name on Linux, macOS and Windows may hold as it is
LONGEST = 120  # characters of a folder name; a longer one keeps its start and a hash of the whole


def safe_name(text: str) -> str:
    """``text`` as one folder name: every other character ('/', spaces, quotes, braces) as '_', and a
    name over :data:`LONGEST` characters cut, with a short hash of the whole so that names stay distinct."""
    name = UNSAFE.sub("_", text)
    if len(name) <= LONGEST:
        return name
    return f"{name[:LONGEST - 9]}_{hashlib.sha256(text.encode()).hexdigest()[:8]}"


def job_dir(overrides: str | None, number: Any) -> str:
    """A sweep job's folder: its overrides as a safe name (:func:`safe_name`), its number without any."""
    return safe_name(overrides) if overrides else str(number)


def job_label(method: str, dataset: str, seed: Any, overrides: str | None) -> str:
    """A run's name in the trackers (and its TensorBoard folder, so a safe name): method, dataset and
    seed, then the job's overrides."""
    label = f"{method}-{dataset}-seed{seed}"
    return safe_name(f"{label}[{overrides}]" if overrides else label)


def tracking_dir(mode: Any, sweep_dir: str, output_dir: str) -> str:
    """The sweep dir for the jobs of a multirun (all their runs in one place), the run dir for a single run."""
    return str(sweep_dir) if str(mode).endswith("MULTIRUN") else str(output_dir)


def sweep_group(mode: Any, sweep_dir: str) -> str | None:
    """The sweep dir for the jobs of a multirun (wandb's group), None for a single run."""
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
    "keyin.job_dir": job_dir,
    "keyin.job_label": job_label,
    "keyin.tracking_dir": tracking_dir,
    "keyin.sweep_group": sweep_group,
    "keyin.wandb_offline": lambda: not wandb_logged_in(),
}.items():
    OmegaConf.register_new_resolver(_name, _resolver, replace=True)
