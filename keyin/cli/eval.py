"""keyin-eval model=random|constant dataset=<name> (or ckpt=<path>): keyframe F1 (paper Table 1);
with video_samples=k also video-prediction PSNR/SSIM of a stage-2 checkpoint (docs/evaluation.md) and
pictures of its rollouts and of k prior samples of the first video_clips clips (the paper's Fig. 5, 10)."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from omegaconf import DictConfig, OmegaConf

from keyin.cli.app import finished_metrics, keyin_main, run_dir, user_errors, write_metrics
from keyin.cli.checks import check_common, require_int_at_least, require_positive_int
from keyin.errors import ConfigError

if TYPE_CHECKING:  # torch and the models are imported when the command runs: --help answers at once
    from torch.utils.data import Dataset

    from keyin.data.clips import ShardClips

BATCH_SIZES = {"cpu": 100, "gpu": 1000}  # batch_size=null: clips per model call on each kind of device


def eval_files(cfg: DictConfig, dataset_name: str) -> list[Path]:
    from keyin.data.hdf5 import split_files

    if cfg.data is not None:
        return [Path(cfg.data)]
    return split_files(Path(cfg.data_dir) / dataset_name, cfg.split)


def eval_clips(cfg: DictConfig, dataset: DictConfig) -> ShardClips:
    """The clips of ``cfg.data`` (or of ``cfg.split`` in ``cfg.data_dir``) at the sizes of ``dataset``."""
    from keyin.data.clips import ShardClips

    return ShardClips(
        eval_files(cfg, dataset.name),
        (dataset.image_size, dataset.image_size, dataset.channels),
        dataset.n_cond,
        dataset.n_future,
    )


def clip_videos(cfg: DictConfig, dataset: DictConfig, count: int) -> list[str] | None:
    """Per clip of the first ``count``, the video keyin-import cut it from (None: generated clips, or a single file)."""
    from keyin.data.hdf5 import read_manifest
    from keyin.data.imports import clip_origins

    folder = Path(cfg.data_dir) / dataset.name
    if cfg.data is not None or "sources" not in read_manifest(folder):
        return None
    return [origin.video for origin in clip_origins(folder, cfg.split)][:count]


def check_discovery(cfg: DictConfig, stage: str | None) -> list[str] | None:
    """``discovery``: null (every rule the checkpoint scores), or a rule or list of rules of a stage-2 checkpoint."""
    if cfg.discovery is None:
        return None
    if stage != "keyframes":
        raise ConfigError(f"discovery={cfg.discovery} chooses among a stage-2 checkpoint's rules; drop it for this model")
    return [cfg.discovery] if isinstance(cfg.discovery, str) else list(cfg.discovery)


def clip_subset(clips: ShardClips, count: int | None) -> Dataset:
    """The first ``count`` clips (all for None)."""
    from torch.utils.data import Subset

    if count is None:
        return clips
    require_positive_int(count, "clips")
    return Subset(clips, range(min(count, len(clips))))


def check_tolerances(cfg: DictConfig) -> list[int]:
    """``tolerances``: the k of each ±k F1, integers >= 0."""
    values = OmegaConf.to_container(cfg.tolerances) if OmegaConf.is_list(cfg.tolerances) else cfg.tolerances
    if not isinstance(values, list) or not all(isinstance(k, int) and not isinstance(k, bool) and k >= 0 for k in values):
        raise ConfigError(f"tolerances={values!r} must be a list of frame counts >= 0, e.g. tolerances=[1,2]")
    return values


def check_video_samples(cfg: DictConfig, stage: str | None) -> None:
    """``video_samples``: 0 (off), or a count of prior samples for a stage-2 checkpoint."""
    require_int_at_least(cfg.video_samples, "video_samples", 0)
    require_positive_int(cfg.video_clips, "video_clips")
    if cfg.video_samples and stage != "keyframes":
        evaluated = f"ckpt= holds a '{stage}' checkpoint" if stage else "a baseline predicts no video"
        raise ConfigError(
            f"video_samples={cfg.video_samples} needs ckpt=<a keyin, jumpy or static run>/checkpoints/"
            f"keyframes/last.ckpt (stage 2), but {evaluated}; drop video_samples="
        )


@user_errors
def evaluate(cfg: DictConfig) -> dict:
    check_common(cfg)
    finished = finished_metrics(run_dir()) if cfg.skip_finished else None
    if finished is not None:
        return finished
    if cfg.batch_size is not None:
        require_positive_int(cfg.batch_size, "batch_size")
    tolerances = check_tolerances(cfg)
    import torch

    from keyin.devices import batch_size_on, choose_device, device_record
    from keyin.eval.discovery import score_methods

    device = choose_device(cfg.device)
    if cfg.ckpt is not None:
        from keyin.decode.registry import Segmentation
        from keyin.decode.rules import SegmentationDiscoverer
        from keyin.lit.registry import load_trained_module

        module, trained = load_trained_module(cfg.ckpt, stage=None, device=device)
        check_video_samples(cfg, module.stage)
        rules = check_discovery(cfg, module.stage)
        name = trained["model"]["name"]
        if module.stage == "interpolator":  # exact best segmentation under the interpolator
            n_keyframes = trained["dataset"]["n_keyframes"]
            discoverers = {f"{name}_{Segmentation.name}": SegmentationDiscoverer(module, n_keyframes)}
        else:
            try:
                discoverers = module.discoverers(name, rules)
            except ValueError as err:
                raise ConfigError(f"discovery={cfg.discovery}: {err}; pick among those") from None
        dataset = OmegaConf.create(trained["dataset"])  # the sizes the model was trained for
        if cfg.compile:
            from keyin.lit.run import compile_frame_networks  # Lightning, only for this

            compile_frame_networks(module)
    elif OmegaConf.select(cfg, "model") is None:
        raise ConfigError("choose what to evaluate: model=random|constant or ckpt=<checkpoint path>")
    elif cfg.model.trainable:
        raise ConfigError(
            f"model={cfg.model.name} must be trained first (keyin-train); evaluate its checkpoint "
            f"with ckpt=<path>"
        )
    else:
        from hydra.utils import instantiate

        check_video_samples(cfg, None)
        check_discovery(cfg, None)
        discoverers, dataset = {cfg.model.name: instantiate(cfg.model.discoverer)}, cfg.dataset
    clips = clip_subset(eval_clips(cfg, dataset), cfg.clips)
    batch_size = batch_size_on(device, cfg.batch_size, **BATCH_SIZES)
    loader = dict(batch_size=batch_size, num_workers=cfg.num_workers, progress=cfg.progress)
    metrics = score_methods(
        discoverers, clips, dataset.n_cond, dataset.n_future, run_dir(), tolerances, clip_videos(cfg, dataset, len(clips)),
        **loader,
    )
    if cfg.video_samples:
        from keyin.pipelines.video import evaluate_video, save_prior_samples, save_rollouts

        torch.manual_seed(cfg.seed)  # the prior samples
        metrics["video"] = evaluate_video(module.model, clips, cfg.video_samples, **loader)
        save_rollouts(module.model, clips, cfg.video_samples, run_dir(), cfg.video_clips)
        metrics["video_pictured"] = save_prior_samples(module.model, clips, cfg.video_samples, run_dir(), cfg.video_clips)
    scored = {"data": str(cfg.data)} if cfg.data is not None else {"split": cfg.split}  # what was scored, and by what
    metrics.update(dataset=dataset.name, seed=cfg.seed, **scored, ckpt=None if cfg.ckpt is None else str(cfg.ckpt),
                   **device_record(device), batch_size=batch_size)
    write_metrics(metrics, run_dir())
    return metrics


main = keyin_main("eval")(evaluate)  # the console script: Hydra, then evaluate(cfg)


if __name__ == "__main__":
    main()
