"""One keyin-train job, its config checked (:mod:`keyin.cli.train`): fit the configured model (KEYIN's
two stages, or Surprise's or TAP's one) with its tracker, score it on the test split and write
metrics.json; untrained baselines (Random, Constant) are only scored.
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import Callable

import lightning as L
import torch
from lightning.pytorch.loggers import Logger
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from keyin import CHOICES_KEY
from keyin.cli.app import config_choice, config_choices, write_metrics
from keyin.cli.checks import is_two_stage
from keyin.cli.tracking import job_logger, log_config, log_results, namespace
from keyin.data.datamodule import ClipDataModule, split_clips
from keyin.devices import choose_device, device_record
from keyin.errors import CheckpointError
from keyin.eval.discovery import score_methods
from keyin.lit.checkpoints import best_of, load_checkpoint, load_stage1, warm_start
from keyin.lit.ranks import is_rank_zero
from keyin.lit.run import fit_stage
from keyin.pretrained import is_pretrained

Discoverers = dict[str, Callable]


def stage1_checkpoint(cfg: DictConfig, stage1_folder: Path) -> Path | str:
    """The checkpoint that stage 2 takes its stage 1 from (a stage-1 one, or a stage-2 one or
    ``pretrained:<name>``, whose frozen stage 1 is taken; ``init_ckpt`` where ``interpolator_ckpt`` is
    not given); one clear error if there is none."""
    given = cfg.interpolator_ckpt or cfg.init_ckpt  # a warm start's checkpoint holds its stage 1
    if given and is_pretrained(given):
        return given
    path = Path(given or stage1_folder / "checkpoints" / "interpolator" / "last.ckpt")
    if not path.is_file():
        raise CheckpointError(
            f"stage 2 starts from a stage-1 checkpoint and {path} does not exist; train stage 1 first "
            f"(stage=both or stage=interpolator) or pass interpolator_ckpt=<run dir>/checkpoints/interpolator/last.ckpt"
        )
    return path


def train_two_stages(cfg: DictConfig, datamodule: Callable, common: dict, folder: Path) -> tuple[Discoverers, float]:
    """KEYIN, Jumpy, Static: stage 1 (into ``stage1_dir`` if set, else this run), then stage 2; the discoverers and the
    job's training seconds (a stage 1 shared through ``stage1_dir`` counts in the jobs that trained it)."""
    scale = cfg.scale
    stage1_folder = Path(cfg.stage1_dir) if cfg.stage1_dir else folder
    seconds = 0.0
    if cfg.stage in ("both", "interpolator"):
        interpolator = instantiate(cfg.model.interpolator)
        if cfg.backbone.frozen_frames:  # backbone=frames: a frame autoencoder's encoder and decoder
            interpolator.load_frame_model(load_checkpoint(cfg.backbone.frames_ckpt, "frames"), cfg.backbone.frames_ckpt)
        with namespace(common["logger"], "stage1"):  # in the trackers: stage1/train/..., then the method's train/...
            fit = fit_stage(
                interpolator,
                datamodule=datamodule(scale.stage1_batch_size),
                max_steps=scale.stage1_steps,
                **dict(common, run_dir=stage1_folder),
            )
        seconds += fit.seconds if fit.trained or stage1_folder == folder else 0.0
    if cfg.stage == "interpolator":
        return {}, seconds
    stage1 = load_stage1(stage1_checkpoint(cfg, stage1_folder))
    module = instantiate(cfg.model.keyframes, stage1=stage1["hyper_parameters"])
    module.load_stage1(stage1["state_dict"])
    if cfg.init_ckpt:  # a warm start; a resumed run's last.ckpt then replaces these weights
        warm_start(module, cfg.init_ckpt)
    seconds += fit_stage(module, datamodule=datamodule(scale.batch_size), max_steps=scale.stage2_steps, **common).seconds
    discoverers = module.to(choose_device(cfg.device)).reader().discoverers(cfg.model.name)  # the fit hands it back on the CPU
    return discoverers, seconds


def run_job(cfg: DictConfig, folder: Path) -> dict | None:
    """Seed, train and score the job into ``folder`` under its tracker; its metrics (None if it scores nothing)."""
    L.seed_everything(cfg.seed, workers=True)
    with job_logger(cfg.logger) as logger:
        log_config(logger, cfg, config_choice("scale"))
        metrics = fit_and_score(cfg, folder, logger)
        if metrics is not None:
            log_results(logger, metrics)
        return metrics


def fit_and_score(cfg: DictConfig, folder: Path, logger: Logger | bool) -> dict | None:
    """Train the configured model into ``folder`` (logging to ``logger``) and score it on the test split."""
    scale, dataset = cfg.scale, cfg.dataset
    device = choose_device(cfg.device)  # where the test split is scored; checked before training
    generator = instantiate(dataset.generator)
    clips = lambda split, size: split_clips(dataset, generator, split, size, cfg.data_dir)  # noqa: E731
    datamodule = lambda batch_size: ClipDataModule(  # noqa: E731
        clips("train", None), clips("val", scale.val_clips), batch_size, cfg.num_workers
    )
    test = clips("test", scale.eval_clips) if scores_test_split(cfg) else None  # its files checked before training
    common = dict(
        run_dir=folder,
        val_every=scale.val_every,
        checkpoint_every=scale.checkpoint_every,
        trainer_kwargs=OmegaConf.to_container(cfg.trainer),
        logger=logger,
        config={**OmegaConf.to_container(cfg, resolve=True), CHOICES_KEY: config_choices()},  # travels in each checkpoint
        compile_networks=cfg.compile,
    )
    module, train_seconds = None, 0.0
    if not cfg.model.trainable:
        discoverers = {cfg.model.name: instantiate(cfg.model.discoverer)}
    elif "module" in cfg.model:  # one stage (Surprise, TAP)
        module = instantiate(cfg.model.module)
        train_seconds = fit_stage(module, datamodule=datamodule(scale.batch_size), max_steps=cfg.model.steps, **common).seconds
        discoverers = module.to(device).discoverers(cfg.model.name)  # the fit hands it back on the CPU
    else:
        discoverers, train_seconds = train_two_stages(cfg, datamodule, common, folder)
    if not cfg.evaluate or not is_rank_zero():  # under DDP, rank 0 alone scores and writes metrics.json
        return None
    # wall times: the stages' fits over every run that resumed them, then this process's scoring; on torch's threads
    times = {"train_seconds": round(train_seconds, 1), "threads": torch.get_num_threads()}
    started = time.perf_counter()
    if discoverers:
        metrics = score_methods(discoverers, test, dataset.n_cond, dataset.n_future, folder)
    elif hasattr(module, "test_metrics"):  # a model without keyframes scores itself (TAP)
        metrics = dict(module.test_metrics(test, folder), method=cfg.model.name)
    else:
        return None
    metrics.update(best_checkpoints(cfg, folder))
    times.update(score_seconds=round(time.perf_counter() - started, 1), **device_record(device))
    return record_metrics(dict(metrics, **times), cfg, folder)


def best_checkpoints(cfg: DictConfig, folder: Path) -> dict:
    """``best``: per stage of the run, its ``best.ckpt``'s monitored metric, value and step (a stage 1
    shared through ``stage1_dir`` included); ``val_f1_best`` and ``val_f1_best_step``: those of the stage
    monitored by validation F1 (the objective of a tuning sweep: ``objective``), None for a model without one."""
    folders = sorted((folder / "checkpoints").glob("*/"))
    if cfg.stage1_dir and is_two_stage(cfg.model):
        folders.append(Path(cfg.stage1_dir) / "checkpoints" / "interpolator")
    best = {path.name: found for path in folders if (found := best_of(path)) is not None}
    by_f1 = next((found for found in best.values() if found["monitor"] == "val/f1"), None)
    return {"best": best, "val_f1_best": by_f1 and by_f1["value"], "val_f1_best_step": by_f1 and by_f1["step"]}


def scores_test_split(cfg: DictConfig) -> bool:
    """Whether the run ends by scoring the test split: ``evaluate``, unless it trains stage 1 only."""
    return bool(cfg.evaluate) and not (is_two_stage(cfg.model) and cfg.stage == "interpolator")


def record_metrics(metrics: dict, cfg: DictConfig, folder: Path) -> dict:
    """Add the run's dataset, seed and scale to ``metrics`` and write metrics.json."""
    metrics.update(
        dataset=cfg.dataset.name, seed=cfg.seed, scale=config_choice("scale"), backbone=config_choice("backbone")
    )
    write_metrics(metrics, folder)
    return metrics
