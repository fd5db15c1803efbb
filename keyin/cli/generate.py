"""keyin-generate dataset=<name>: write a dataset's splits as HDF5 shards with a manifest."""

from __future__ import annotations

from pathlib import Path

from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from keyin.cli.app import keyin_main, run_dir, user_errors, write_metrics
from keyin.cli.checks import check_common, require_positive_int
from keyin.data.generate import generate_dataset
from keyin.errors import ConfigError


@user_errors
def generate(cfg: DictConfig) -> dict:
    check_common(cfg)
    if cfg.dataset.generator is None:
        raise ConfigError(
            f"dataset={cfg.dataset.name} has no generator: its clips are imported, not generated; import "
            f"them with `keyin-import source=<videos> dataset={cfg.dataset.name}`"
        )
    require_positive_int(cfg.shard_size, "shard_size")
    require_positive_int(cfg.workers, "workers")
    splits = OmegaConf.to_container(cfg.splits)
    for split, count in splits.items():
        require_positive_int(count, f"splits.{split}")
    stats = generate_dataset(
        generator=instantiate(cfg.dataset.generator),
        folder=Path(cfg.data_dir) / cfg.dataset.name,
        dataset=cfg.dataset.name,
        splits=splits,
        shard_size=cfg.shard_size,
        seed=cfg.seed,
        workers=cfg.workers,
        config=OmegaConf.to_container(cfg.dataset.generator, resolve=True),
        progress=cfg.progress,
    )
    write_metrics(dict(stats, dataset=cfg.dataset.name, folder=str(Path(cfg.data_dir) / cfg.dataset.name)), run_dir())
    return stats


main = keyin_main("generate")(generate)  # the console script: Hydra, then generate(cfg)


if __name__ == "__main__":
    main()
