"""keyin-figures figure=fig4|fig5|fig6|fig7 ckpt=<stage-2 checkpoint> [ckpt_jumpy=...] [out=<folder>]:
one of the paper's figures from trained models, ``<out>/<figure>_<what>_<dataset>.png`` and a JSON
of the numbers it shows beside it."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from typing import Any, Callable

import numpy as np
import torch
from hydra.utils import instantiate
from omegaconf import DictConfig, OmegaConf

from keyin import __version__
from keyin.cli.app import keyin_main, machine, run_dir, user_errors, write_metrics
from keyin.cli.checks import require_int_at_least, require_positive_int, require_seed
from keyin.cli.eval import eval_clips, eval_files
from keyin.data.clips import ShardClips
from keyin.data.hdf5 import load_arrays
from keyin.devices import choose_device, device_record
from keyin.errors import ConfigError
from keyin.io import atomic_write_text
from keyin.lit.registry import load_trained_module
from keyin.models import KEYIN
from keyin.pipelines.figures import MODES, save_comparison, save_trajectory_figure
from keyin.pipelines.video import save_prior_samples

# figure -> what its file is called after
FIGURES = {"fig4": "reconstructions", "fig5": "prior_samples", "fig6": "trajectories", "fig7": "predictions"}
PUSHING_ONLY = ("fig6", "fig7")
SIZES = ("name", "image_size", "channels", "n_cond", "n_future")  # what two compared models must share
SCENE = ("wall", "side", "goal", "puck", "pusher")  # what fig6 reads of each test clip besides its frames


def stage2_model(cfg: DictConfig, key: str) -> tuple[KEYIN, dict[str, Any]]:
    """The KEYIN model (KEYIN, Jumpy or Static) of the stage-2 checkpoint at ``cfg[key]`` and its run config."""
    if cfg[key] is None:
        raise ConfigError(
            f"figure={cfg.figure} needs {key}=<run dir>/checkpoints/keyframes/last.ckpt, the stage-2 checkpoint "
            f"of a KEYIN, Jumpy or Static run"
        )
    module, trained = load_trained_module(cfg[key], stage="keyframes", device=choose_device(cfg.device))
    return module.model, trained


def fig4(cfg: DictConfig, model: KEYIN, trained: dict, clips: ShardClips, path: Path) -> dict[str, Any]:
    jumpy, other = stage2_model(cfg, "ckpt_jumpy")
    theirs, ours = (", ".join(f"{key}={config['dataset'][key]}" for key in SIZES) for config in (other, trained))
    if theirs != ours:
        raise ConfigError(
            f"ckpt_jumpy= holds a model of dataset {theirs} but ckpt= one of dataset {ours}; compare two models of "
            f"one dataset and size"
        )
    name, jumpy_name = trained["model"]["name"], other["model"]["name"]
    models = {name: model, jumpy_name if jumpy_name != name else f"{name} (ckpt_jumpy)": jumpy}
    return {"ckpt_jumpy": str(cfg.ckpt_jumpy), **save_comparison(models, clips, cfg.n, "posterior", 1, path)}


def fig5(cfg: DictConfig, model: KEYIN, trained: dict, clips: ShardClips, path: Path) -> dict[str, Any]:
    return save_prior_samples(model, clips, cfg.k, path.parent, cfg.n, name=path.stem)


def fig6(cfg: DictConfig, model: KEYIN, trained: dict, clips: ShardClips, path: Path) -> dict[str, Any]:
    if not 0 <= cfg.start < len(clips):
        raise ConfigError(f"start={cfg.start} must be the index of one of the {len(clips)} clips")
    files = eval_files(cfg, trained["dataset"]["name"])
    try:
        stored = [load_arrays(file, SCENE) for file in files]
    except KeyError:
        raise ConfigError(
            f"fig6 reads each clip's scene ({', '.join(SCENE)}), which {', '.join(map(str, files))} lack; pass "
            f"the pushing clips that keyin-generate dataset=pushing writes"
        ) from None
    scenes = {name: np.concatenate([arrays[name] for arrays in stored]) for name in SCENE}
    generator = None
    if cfg.demos:
        if importlib.util.find_spec("dm_control") is None:
            raise ConfigError(f"demos={cfg.demos} runs the demonstrator, which needs pip install 'keyin[sim]'; or pass demos=0")
        generator = instantiate(trained["dataset"]["generator"])
    return save_trajectory_figure(
        model, clips, scenes, cfg.start, cfg.trajectories, path, generator, cfg.demos, cfg.seed, cfg.batch_size
    )


def fig7(cfg: DictConfig, model: KEYIN, trained: dict, clips: ShardClips, path: Path) -> dict[str, Any]:
    return save_comparison({trained["model"]["name"]: model}, clips, cfg.n, cfg.mode, cfg.k, path)


DRAW: dict[str, Callable[[DictConfig, KEYIN, dict, ShardClips, Path], dict[str, Any]]] = {
    "fig4": fig4, "fig5": fig5, "fig6": fig6, "fig7": fig7,
}


def check_figures(cfg: DictConfig) -> None:
    if cfg.figure not in FIGURES:
        chosen = "choose one with figure=" if cfg.figure is None else f"figure={cfg.figure} must be"
        raise ConfigError(f"{chosen} one of {', '.join(FIGURES)}")
    if cfg.mode not in MODES:
        raise ConfigError(f"mode={cfg.mode} must be one of {', '.join(MODES)}")
    require_seed(cfg.seed)
    for key in ("n", "k", "trajectories", "batch_size"):
        require_positive_int(cfg[key], key)
    for key in ("start", "demos"):
        require_int_at_least(cfg[key], key, 0)


PUSHING_GENERATOR = "keyin.data.pushing.PushingGenerator"  # dataset=pushing and pushing_irregular


@user_errors
def figures(cfg: DictConfig) -> dict[str, Any]:
    check_figures(cfg)
    model, trained = stage2_model(cfg, "ckpt")
    dataset = OmegaConf.create(trained["dataset"])  # the sizes the model was trained for
    if cfg.figure in PUSHING_ONLY and OmegaConf.select(dataset, "generator._target_") != PUSHING_GENERATOR:
        raise ConfigError(
            f"figure={cfg.figure} draws the pushing scene, but ckpt= holds a model of dataset={dataset.name}; "
            f"pass a pushing checkpoint"
        )
    clips = eval_clips(cfg, dataset)
    path = Path(cfg.out or run_dir()) / f"{cfg.figure}_{FIGURES[cfg.figure]}_{dataset.name}.png"
    torch.manual_seed(cfg.seed)  # the prior samples
    numbers = DRAW[cfg.figure](cfg, model, trained, clips, path)
    numbers = {"figure": cfg.figure, "png": str(path), "ckpt": str(cfg.ckpt), "model": trained["model"]["name"],
               "dataset": dataset.name, "seed": cfg.seed, **numbers, **device_record(choose_device(cfg.device)),
               "keyin_version": __version__, "machine": machine()}
    atomic_write_text(path.with_suffix(".json"), json.dumps(numbers, indent=1, sort_keys=True))
    write_metrics(numbers, run_dir())
    return numbers


main = keyin_main("figures")(figures)  # the console script: Hydra, then figures(cfg)


if __name__ == "__main__":
    main()
