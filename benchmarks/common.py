"""What the benchmark scripts share: the machine's name, writing the Markdown result, a split's clips."""

from __future__ import annotations

import argparse
import platform
import subprocess
from pathlib import Path
from typing import Any

from hydra import compose, initialize_config_module
from omegaconf import DictConfig
from torch.utils.data import DataLoader, Subset

from keyin.cli.app import CONFIG_MODULE
from keyin.data.clips import ShardClips
from keyin.data.hdf5 import split_files


def cpu_model() -> str:
    """The CPU's model name (``lscpu``), or what ``platform`` knows."""
    try:
        lines = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout.splitlines()
    except (OSError, subprocess.CalledProcessError):
        return platform.processor() or "unknown"
    names = [line.split(":", 1)[1].strip() for line in lines if line.startswith("Model name")]
    return names[0] if names else "unknown"


def publish(report: str, out: Path | None) -> None:
    """Print the Markdown report and write it to ``out`` if given."""
    print(report)
    if out:
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(report)


def clip_arguments(parser: argparse.ArgumentParser, clips: int) -> argparse.ArgumentParser:
    """The options every script on a split's clips takes: ``--clips``, ``--split`` (default ``val``:
    choices are made on validation clips, never on the test set), ``--data-dir`` and ``--out``."""
    parser.add_argument("--clips", type=int, default=clips)
    parser.add_argument("--split", default="val")
    parser.add_argument("--data-dir", default="data")
    parser.add_argument("--out", type=Path)
    return parser


def dataset_config(dataset_name: str) -> DictConfig:
    """conf/dataset/<name>.yaml as the commands compose it, its defaults list included
    (``pushing_irregular`` extends ``pushing``)."""
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        return compose("eval", overrides=[f"dataset={dataset_name}"]).dataset


def split_batch(dataset_name: str, split: str, clips: int, data_dir: str) -> tuple[Any, dict[str, Any]]:
    """The dataset's config (:func:`dataset_config`) and the first ``clips`` clips of one of its
    generated splits (``<data_dir>/<name>/``) as one batch."""
    dataset = dataset_config(dataset_name)
    image = (dataset.image_size, dataset.image_size, dataset.channels)
    shards = ShardClips(split_files(Path(data_dir) / dataset_name, split), image, dataset.n_cond, dataset.n_future)
    shards = Subset(shards, range(min(clips, len(shards))))
    return dataset, next(iter(DataLoader(shards, batch_size=len(shards))))
