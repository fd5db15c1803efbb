"""keyin-train experiment=<name>: stage 1 (interpolator), stage 2 (keyframes), then keyframe F1."""

from __future__ import annotations

from pathlib import Path

import hydra
import lightning as L
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from keyin.cli.app import CONFIG_DIR, run_dir, user_errors, write_metrics
from keyin.cli.checks import check_common, check_training
from keyin.data.datamodule import ClipDataModule, split_clips
from keyin.eval.discovery import evaluate_discoverer, save_examples
from keyin.lit.checkpoints import load_checkpoint
from keyin.lit.run import fit_stage


@user_errors
def train(cfg: DictConfig) -> dict | None:
    check_common(cfg)
    check_training(cfg)
    L.seed_everything(cfg.seed, workers=True)
    folder, scale, dataset = run_dir(), cfg.scale, cfg.dataset
    generator = instantiate(dataset.generator)
    clips = lambda split, size: split_clips(dataset, generator, split, size, cfg.data_dir)  # noqa: E731
    datamodule = lambda batch_size: ClipDataModule(  # noqa: E731
        clips("train", None), clips("val", scale.val_clips), batch_size, cfg.num_workers
    )
    common = dict(
        run_dir=folder,
        val_every=scale.val_every,
        checkpoint_every=scale.checkpoint_every,
        trainer_kwargs=OmegaConf.to_container(cfg.trainer),
        logger=instantiate(cfg.logger) if cfg.logger else False,
        config=OmegaConf.to_container(cfg, resolve=True),
    )
    if cfg.stage in ("both", "interpolator"):
        fit_stage(
            instantiate(cfg.model.interpolator),
            datamodule=datamodule(scale.stage1_batch_size),
            max_steps=scale.stage1_steps,
            **common,
        )
    if cfg.stage == "interpolator":
        return None
    stage1 = load_checkpoint(
        cfg.interpolator_ckpt or folder / "checkpoints" / "interpolator" / "last.ckpt", "interpolator"
    )
    module = instantiate(cfg.model.keyframes, stage1=stage1["hyper_parameters"])
    module.load_stage1(stage1["state_dict"])
    fit_stage(module, datamodule=datamodule(scale.batch_size), max_steps=scale.stage2_steps, **common)
    if not cfg.evaluate:
        return None
    test_clips = clips("test", scale.eval_clips)
    scores = evaluate_discoverer(module.discover, test_clips, dataset.n_future)
    save_examples(module.discover, test_clips, dataset.n_cond, folder)
    metrics = dict(scores, method=cfg.model.name, dataset=dataset.name)
    write_metrics(metrics, folder)
    return metrics


@hydra.main(config_path=CONFIG_DIR, config_name="train", version_base="1.3")
def main(cfg: DictConfig) -> None:
    train(cfg)


if __name__ == "__main__":
    main()
