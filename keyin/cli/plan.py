"""keyin-plan planner=<name>: play the fixed pushing planning tasks (paper Table 2).

One JSON line per finished task in ``<run dir>/tasks.jsonl``; the same command with
``resume=<run dir>`` (or a sweep's fixed job dir) skips the finished tasks. ``metrics.json`` (and
the last line printed) holds the mean ± std position error and the success rate over the tasks.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING, Any

from omegaconf import DictConfig, ListConfig, OmegaConf

from keyin.cli.app import keyin_main, run_dir, user_errors, write_metrics
from keyin.cli.checks import check_common, require_positive_int
from keyin.errors import ConfigError, DatasetFormatError
from keyin.io import atomic_write_text, sha256_of
from keyin.planning.journal import claim_run_dir
from keyin.pretrained import resolve

if TYPE_CHECKING:  # numpy, scipy, h5py and the planners are imported when the command runs: --help answers at once
    from keyin.planning.tasks import PlanningTask


def task_files(cfg: DictConfig) -> list[Path]:
    from keyin.data.hdf5 import split_files
    from keyin.data.pushing import PLANNING_SPLIT

    if cfg.data is not None:
        return [Path(cfg.data)]
    try:
        return split_files(Path(cfg.data_dir) / cfg.dataset.name, PLANNING_SPLIT)
    except DatasetFormatError as err:
        raise DatasetFormatError(
            f"{err} (the planning tasks: keyin-generate dataset=pushing 'splits={{{PLANNING_SPLIT}: 240}}')"
        ) from None


def task_indices(value: Any, key: str) -> frozenset[int] | None:
    """``tasks``/``pictures``: an integer n (the tasks 0 … n-1) or a list of task indices; None for
    ``tasks=null`` (all)."""
    if value is None and key == "tasks":
        return None
    if isinstance(value, int) and not isinstance(value, bool) and value >= 0:
        return frozenset(range(value))
    items = list(value) if isinstance(value, (list, ListConfig)) else None
    if items is None or not all(isinstance(i, int) and not isinstance(i, bool) and i >= 0 for i in items):
        raise ConfigError(f"{key}={value!r} must be an integer n >= 0 (the tasks 0 … n-1) or a list of task indices, "
                          f"e.g. '{key}=[6,10]'")
    return frozenset(items)


def select_tasks(tasks: list[PlanningTask], value: Any) -> list[PlanningTask]:
    """``tasks``: null (all), n (the first n) or a list of task indices, each of which must exist."""
    if value is None or isinstance(value, int):
        return tasks[:value]
    wanted = task_indices(value, "tasks")
    missing = sorted(wanted - {task.index for task in tasks})
    if missing:
        raise ConfigError(f"tasks: no task with index {missing} in the planning files ({len(tasks)} tasks)")
    return [task for task in tasks if task.index in wanted]


def write_model_config(checkpoint: str, folder: Path) -> DictConfig:
    """The run config stored in ``checkpoint`` (a path or ``pretrained:<name>``), written as the planning job's
    ``<folder>/model_config.yaml``: keyin-report names a row of the paper's method after the model planned with."""
    from keyin.checkpoints import load_checkpoint
    from keyin.eval.planning import MODEL_CONFIG
    from keyin.lit.registry import run_config

    model_config = OmegaConf.create(run_config(load_checkpoint(resolve(checkpoint))))
    atomic_write_text(folder / MODEL_CONFIG, OmegaConf.to_yaml(model_config))
    return model_config


def check_plan(cfg: DictConfig) -> float:
    """The checks beyond the common ones; returns the success threshold."""
    check_common(cfg)
    require_positive_int(cfg.workers, "workers")
    if task_indices(cfg.tasks, "tasks") == frozenset():
        raise ConfigError(f"tasks={cfg.tasks!r} plays nothing; give n >= 1, a list of task indices or null (all)")
    task_indices(cfg.pictures, "pictures")
    if not isinstance(cfg.outcome_pictures, bool):
        raise ConfigError(f"outcome_pictures={cfg.outcome_pictures!r} must be true or false")
    threshold = cfg.success_threshold
    if isinstance(threshold, bool) or not isinstance(threshold, (int, float)) or not threshold > 0:
        raise ConfigError(f"success_threshold={threshold!r} must be a positive number (world units)")
    return float(threshold)


@user_errors
def plan(cfg: DictConfig) -> dict:
    import numpy as np
    from hydra.utils import instantiate

    from keyin.eval.planning import planning_summary
    from keyin.planning.runner import PlanJob, run_tasks
    from keyin.planning.servo import ServoParams
    from keyin.planning.tasks import read_tasks, task_generator

    threshold = check_plan(cfg)
    servo = ServoParams.from_config(cfg.planner)
    controller = instantiate(cfg.planner.controller)  # a learned planner loads (and checks) its checkpoint
    files = task_files(cfg)
    tasks, generator_config = read_tasks(files)
    tasks = select_tasks(tasks, cfg.tasks)
    folder = run_dir()
    checkpoint = cfg.planner.get("checkpoint")
    claim_run_dir(folder, {
        "planner": {k: v for k, v in OmegaConf.to_container(cfg.planner, resolve=True).items() if k != "servo_threads"},
        "seed": cfg.seed,
        "success_threshold": threshold,
        "task_files": {path.name: sha256_of(path) for path in files},
        **({"checkpoint_sha256": sha256_of(resolve(checkpoint))} if checkpoint else {}),  # resuming refuses a retrained one
    })
    if checkpoint:
        write_model_config(checkpoint, folder)
    job = PlanJob(
        planner=cfg.planner.name,
        controller=controller,
        servo=servo,
        generator=task_generator(generator_config),
        seed=cfg.seed,
        threshold=threshold,
        pictures=task_indices(cfg.pictures, "pictures"),
        picture_dir=folder / "pictures",
        outcome_pictures=cfg.outcome_pictures,
    )
    records, counts = run_tasks(job, tasks, folder / "tasks.jsonl", cfg.workers, cfg.progress)
    if counts["skipped"]:
        print(f"{counts['skipped']} of {len(tasks)} tasks finished earlier in {folder}; skipped")
    metrics = planning_summary(
        np.array([r["final_error"] for r in records]), np.array([r["initial_distance"] for r in records]), threshold
    )
    metrics.update(
        planner=cfg.planner.name,
        servo_observe=servo.observe,  # the servo setting (keyin-report names a row of another than the default)
        servo_action_repeat=servo.action_repeat,
        servo_horizon=servo.horizon,
        dataset=cfg.dataset.name,
        seed=cfg.seed,
        # the seed of the model planned with, where it can differ from the planning seed (keyin, jumpy)
        **({"model_seed": cfg.planner.model_seed} if "model_seed" in cfg.planner else {}),
        success_threshold=threshold,
        steps_mean=float(np.mean([r["steps"] for r in records])),
        seconds_per_task=float(np.mean([r["seconds"] for r in records])),
        **counts,
    )
    write_metrics(metrics, folder)
    return metrics


main = keyin_main("plan")(plan)  # the console script: Hydra, then plan(cfg)


if __name__ == "__main__":
    main()
