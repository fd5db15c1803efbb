"""Experiment trackers at the edge of a job: online/offline, the job's config and results, stage
namespaces, finish.

``keyin.cli.naming`` registers the resolvers the logger configs name their runs and groups with (and
``${keyin.wandb_offline:}``). Everything sent to a tracker is sent from rank zero only.
"""

from __future__ import annotations

import contextlib
import math
from typing import Any, Iterator, Mapping

from hydra.utils import instantiate
from lightning.pytorch.loggers import Logger, TensorBoardLogger, WandbLogger
from lightning.pytorch.utilities import rank_zero_only
from omegaconf import DictConfig, OmegaConf

import keyin.cli.naming  # noqa: F401  (registers the job naming resolvers)

TEST_SCORES = ("f1", "f1_interior", "f1_with_ends", "f1_tol1_interior")  # metrics.json → test/<score>
RESULTS = (*(f"test/{score}" for score in TEST_SCORES), "val/f1_best", "val/f1_best_step")  # TensorBoard's HParams metrics




@contextlib.contextmanager
def job_logger(config: DictConfig | None) -> Iterator[Any]:
    """The job's Lightning logger (False for ``logger=none``); a wandb run it started is finished on
    exit (exit code 1 if the job raised), so the next job of a sweep in this process gets its own
    run instead of Lightning reusing ``wandb.run``."""
    logger = instantiate(config) if config else False
    if isinstance(logger, WandbLogger) and logger._wandb_init.get("anonymous", False) is None:
        del logger._wandb_init["anonymous"]  # Lightning passes anonymous=None, which wandb warns has no effect
    failed = True
    try:
        yield logger
        failed = False
    finally:
        if isinstance(logger, WandbLogger) and logger._experiment is not None:
            logger.experiment.finish(exit_code=1 if failed else 0)


def flat(config: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """A nested config as ``a/b/c`` keys, each value a number, a bool or a string (TensorBoard's hparams)."""
    out: dict[str, Any] = {}
    for key, value in config.items():
        name = f"{prefix}{key}"
        if isinstance(value, Mapping):
            out |= flat(value, f"{name}/")
        else:
            out[name] = value if isinstance(value, (bool, int, float, str)) else str(value)
    return out


@rank_zero_only
def log_config(logger: Logger | bool, cfg: DictConfig, scale: str | None) -> None:
    """Send the job's whole resolved config to the tracker: nested into wandb's config (with ``method``
    and ``scale_preset`` beside it); flattened as TensorBoard's hyperparameters, with Method, Dataset,
    Seed and Scale (the preset) on top and :data:`RESULTS` declared as the HParams metrics."""
    config = OmegaConf.to_container(cfg, resolve=True)
    if isinstance(logger, WandbLogger):
        logger.experiment.config.update({"method": cfg.model.name, "scale_preset": scale, **config}, allow_val_change=True)
    elif isinstance(logger, TensorBoardLogger):
        from torch.utils.tensorboard.summary import hparams

        # capitalised, so that they sort first (TensorBoard orders the hyperparameters that differ between runs
        # first, then by name; lower-case config keys follow)
        top = {"Method": cfg.model.name, "Dataset": cfg.dataset.name, "Seed": cfg.seed, "Scale": str(scale)}
        writer = logger.experiment._get_file_writer()
        for summary in hparams(top | flat(config), dict.fromkeys(RESULTS, 0.0)):
            writer.add_summary(summary)


def results(metrics: Mapping[str, Any]) -> dict[str, float]:
    """A job's results as the trackers get them: its test scores and its best validation F1 and step."""
    found = {f"test/{score}": metrics[score] for score in TEST_SCORES if score in metrics}
    if metrics.get("val_f1_best") is not None:
        found |= {"val/f1_best": metrics["val_f1_best"], "val/f1_best_step": metrics["val_f1_best_step"]}
    return {key: float(value) for key, value in found.items() if not math.isnan(float(value))}


@rank_zero_only
def log_results(logger: Logger | bool, metrics: Mapping[str, Any]) -> None:
    """Send :func:`results` as metrics (TensorBoard's HParams table reads them) and into wandb's summary."""
    found = results(metrics)
    if not logger or not found:
        return
    logger.log_metrics(found)
    if isinstance(logger, WandbLogger):
        logger.experiment.summary.update(found)
    logger.save()


@contextlib.contextmanager
def namespace(logger: Logger | bool, prefix: str) -> Iterator[None]:
    """Metrics sent to TensorBoard or wandb inside the block are named ``<prefix>/<key>`` (stage 1's
    ``stage1/train/loss`` beside the method's ``train/loss``); the CSV logger keeps its columns."""
    tracker = logger if isinstance(logger, (TensorBoardLogger, WandbLogger)) else None
    if tracker is not None:
        tracker._prefix, tracker.LOGGER_JOIN_CHAR = prefix, "/"  # Lightning's own key prefix, joined by '/'
    try:
        yield
    finally:
        if tracker is not None:
            tracker._prefix = ""
            del tracker.LOGGER_JOIN_CHAR
