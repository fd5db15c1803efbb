"""keyin-eval model=random|constant dataset=<name> (or ckpt=<path>): keyframe F1 (paper Table 1)."""

from __future__ import annotations

from pathlib import Path

from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from keyin.cli.app import keyin_main, run_dir, user_errors, write_metrics
from keyin.cli.checks import check_common, require_positive_int
from keyin.data.clips import ShardClips
from keyin.data.hdf5 import split_files
from keyin.errors import ConfigError
from keyin.eval.discovery import score_methods
from keyin.eval.segmentation import SegmentationDiscoverer
from keyin.lit.checkpoints import load_trained_module


def eval_files(cfg: DictConfig, dataset_name: str) -> list[Path]:
    if cfg.data is not None:
        return [Path(cfg.data)]
    return split_files(Path(cfg.data_dir) / dataset_name, cfg.split)


@user_errors
def evaluate(cfg: DictConfig) -> dict:
    check_common(cfg)
    require_positive_int(cfg.batch_size, "batch_size")
    if cfg.ckpt is not None:
        module, trained = load_trained_module(cfg.ckpt, stage=None)
        name = trained["model"]["name"]
        if module.stage == "interpolator":  # exact best segmentation under the interpolator
            n_keyframes = trained["dataset"]["n_keyframes"]
            discoverers = {f"{name}_segmentation": SegmentationDiscoverer(module, n_keyframes)}
        else:
            discoverers = module.discoverers(name)
        dataset = OmegaConf.create(trained["dataset"])  # the sizes the model was trained for
    elif OmegaConf.select(cfg, "model") is None:
        raise ConfigError("choose what to evaluate: model=random|constant or ckpt=<checkpoint path>")
    elif cfg.model.trainable:
        raise ConfigError(
            f"model={cfg.model.name} must be trained first (keyin-train); evaluate its checkpoint "
            f"with ckpt=<path>"
        )
    else:
        discoverers, dataset = {cfg.model.name: instantiate(cfg.model.discoverer)}, cfg.dataset
    clips = ShardClips(
        eval_files(cfg, dataset.name),
        (dataset.image_size, dataset.image_size, dataset.channels),
        dataset.n_cond,
        dataset.n_future,
    )
    metrics = score_methods(
        discoverers, clips, dataset.n_cond, dataset.n_future, run_dir(),
        batch_size=cfg.batch_size, num_workers=cfg.num_workers, progress=cfg.progress,
    )
    metrics.update(dataset=dataset.name, seed=cfg.seed)
    write_metrics(metrics, run_dir())
    return metrics


@keyin_main("eval")
def main(cfg: DictConfig) -> None:
    evaluate(cfg)


if __name__ == "__main__":
    main()
