"""What every entry point shares: where conf/ is, one-line errors, the run dir, metrics.json."""

from __future__ import annotations

import functools
import json
import sys
from pathlib import Path
from typing import Any, Callable, Mapping

from hydra.core.hydra_config import HydraConfig
from hydra.errors import InstantiationException
from omegaconf import DictConfig, OmegaConf

from keyin.data.hdf5 import atomic_write_text
from keyin.errors import KeyinError

CONFIG_DIR = str(Path(__file__).resolve().parents[2] / "conf")

# ${keyin.default:value,fallback}: the fallback when value is null (resume= picks the run dir).
OmegaConf.register_new_resolver(
    "keyin.default", lambda value, fallback: fallback if value is None else value, replace=True
)


def fail(message: str) -> None:
    """Print one error line and exit with status 2 (bad input, not a crash)."""
    print(f"error: {message}", file=sys.stderr)
    sys.exit(2)


def user_errors(task: Callable[[DictConfig], Any]) -> Callable[[DictConfig], Any]:
    """Turn a ``KeyinError`` (or a bad value caught while instantiating) into one error line."""

    @functools.wraps(task)
    def wrapper(cfg: DictConfig) -> Any:
        try:
            return task(cfg)
        except KeyinError as err:
            fail(str(err))
        except InstantiationException as err:
            cause = err.__cause__
            if isinstance(cause, (ValueError, KeyinError)):
                fail(str(cause))
            raise

    return wrapper


def run_dir() -> Path:
    """The Hydra output dir of the current job."""
    return Path(HydraConfig.get().runtime.output_dir)


def config_choice(group: str) -> str | None:
    """The option chosen for a config group in the current job (e.g. ``scale`` → ``cpu``)."""
    return HydraConfig.get().runtime.choices.get(group)


def write_metrics(metrics: Mapping[str, Any], folder: Path) -> Path:
    """Write ``metrics.json`` atomically and print the metrics as the last line of output."""
    path = Path(folder) / "metrics.json"
    atomic_write_text(path, json.dumps(dict(metrics), indent=1, sort_keys=True))
    print(json.dumps(dict(metrics), sort_keys=True))
    return path
