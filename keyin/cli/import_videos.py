"""keyin-import source=<videos>: your own videos (files, frame folders, arrays, robomimic HDF5, LeRobot folders) as a
keyin dataset in <data_dir>/<dataset name>/, for keyin-train and keyin-eval."""

from __future__ import annotations

import math
import sys
from pathlib import Path

from omegaconf import DictConfig, OmegaConf

from keyin.cli.app import keyin_main, run_dir, user_errors, write_metrics
from keyin.cli.checks import check_common, optional_name, require_int_at_least, require_positive_int
from keyin.data.frames import CHANNELS
from keyin.data.imports import ImportSpec, import_videos
from keyin.errors import ConfigError


def check_import(cfg: DictConfig) -> dict[str, float]:
    """What keyin-import needs beyond the common checks; returns the split fractions."""
    if cfg.source is None:
        raise ConfigError(
            "source= is required: a video file, a folder of videos or of PNG/JPG frames, an .npy/.npz "
            "array file, a robomimic-style .hdf5 or a LeRobot v2 dataset folder"
        )
    if cfg.dataset.channels not in CHANNELS:
        raise ConfigError(f"dataset.channels={cfg.dataset.channels} must be 1 (grey) or 3 (RGB) to import videos")
    for key in ("frame_stride", "min_future", "shard_size"):
        require_positive_int(cfg[key], key)
    require_int_at_least(cfg.window_stride, "window_stride", 0)
    if cfg.fps is not None and not (isinstance(cfg.fps, (int, float)) and cfg.fps > 0):
        raise ConfigError(f"fps={cfg.fps!r} must be a positive number (frames per second) or null")
    fractions = OmegaConf.to_container(cfg.fractions)
    if not isinstance(fractions, dict) or not fractions or not all(
        isinstance(v, (int, float)) and not isinstance(v, bool) and v >= 0 for v in fractions.values()
    ) or not math.isclose(sum(fractions.values()), 1.0, abs_tol=1e-6):
        raise ConfigError(
            f"fractions={fractions} must give each split a share >= 0, the shares summing to 1; a "
            f"command-line dict merges into the default, so name every split (e.g. "
            f"fractions='{{train: 1.0, val: 0, test: 0}}')"
        )
    return {str(split): float(share) for split, share in fractions.items()}


@user_errors
def import_command(cfg: DictConfig) -> dict:
    check_common(cfg)
    fractions = check_import(cfg)
    dataset = cfg.dataset
    spec = ImportSpec(
        image_size=dataset.image_size, channels=dataset.channels, n_cond=dataset.n_cond, n_future=dataset.n_future,
        frame_stride=cfg.frame_stride, window_stride=cfg.window_stride, min_future=cfg.min_future,
        binary=bool(cfg.binary), fps=cfg.fps, camera_key=optional_name(cfg.camera_key),
    )
    folder = Path(cfg.data_dir) / dataset.name
    stats = import_videos(
        source=Path(cfg.source), folder=folder, dataset=dataset.name, spec=spec, fractions=fractions,
        seed=cfg.seed, shard_size=cfg.shard_size, labels=Path(cfg.labels) if cfg.labels else None,
        overwrite=bool(cfg.overwrite), progress=cfg.progress,
    )
    for warning in stats["warnings"]:
        print(f"warning: {warning}", file=sys.stderr)
    write_metrics(dict(stats, dataset=dataset.name, folder=str(folder)), run_dir())
    return stats


main = keyin_main("import")(import_command)  # the console script: Hydra, then import_command(cfg)


if __name__ == "__main__":
    main()
