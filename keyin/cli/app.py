"""What every entry point shares: where the configs are, one-line errors, the run dir, metrics.json."""

from __future__ import annotations

import contextlib
import difflib
import errno
import functools
import json
import logging
import os
import platform
import sys
import warnings
from pathlib import Path
from typing import Any, Callable, Iterator, Mapping

import hydra
from hydra.core.hydra_config import HydraConfig
from hydra.errors import ConfigCompositionException, InstantiationException, OverrideParseException
from omegaconf import DictConfig, OmegaConf
from omegaconf.errors import ConfigAttributeError, ConfigKeyError

import keyin.cli.naming  # noqa: F401  (registers the logger configs' resolvers)
from keyin import CONFIG_MODULE, __version__
from keyin.cli.checks import moved_key_message
from keyin.errors import KeyinError
from keyin.io import atomic_write_text

# ${keyin.default:value,fallback}: the fallback when value is null (resume= picks the run dir).
OmegaConf.register_new_resolver(
    "keyin.default", lambda value, fallback: fallback if value is None else value, replace=True
)


class LightningTips(logging.Filter):
    """Drops Lightning's advertisements ("💡 Tip: ... try installing litlogger"), nothing else."""

    def filter(self, record: logging.LogRecord) -> bool:
        return not str(record.getMessage()).startswith("💡 Tip")


def quiet_expected_library_output() -> None:
    """Keep a run's output to what a user acts on: Lightning's install tips and a deprecation inside
    Lightning's own pytree helper (printed at every fit, nothing a keyin user can change) are
    dropped. Warnings about the user's data or config are never filtered."""
    warnings.filterwarnings("ignore", message=r"`isinstance\(treespec, LeafSpec\)` is deprecated")
    lightning = logging.getLogger("lightning.pytorch.utilities.rank_zero")
    if not any(isinstance(existing, LightningTips) for existing in lightning.filters):
        lightning.addFilter(LightningTips())


# Libraries whose INFO lines say nothing a user acts on (absl: "MUJOCO_GL=egl, attempting to import
# ...", "MuJoCo library version is ..."; OpenGL: "No OpenGL_accelerate module loaded"); verbose=true shows them.
CHATTY_LIBRARIES = ("absl", "OpenGL")


def show_library_info(verbose: bool) -> None:
    """Hide (or, with ``verbose``, show) the INFO lines of :data:`CHATTY_LIBRARIES`; their warnings
    and errors are always shown."""
    for name in CHATTY_LIBRARIES:
        logging.getLogger(name).setLevel(logging.NOTSET if verbose else logging.WARNING)


def fail(message: str) -> None:
    """Print one error line and exit with status 2 (bad input, not a crash)."""
    print(f"error: {message}", file=sys.stderr)
    sys.exit(2)


# The fix named when the file system refuses a file (errno → fix).
WRITABLE_FOLDER = "choose a writable folder with hydra.run.dir= (the run dir) or data_dir= (datasets)"
FILE_SYSTEM_FIXES = {
    errno.ENOSPC: "free disk space (or point data_dir= / hydra.run.dir= at another disk) and run the "
    "same command again: finished shards and checkpoints are kept",
    errno.EDQUOT: "free space within your quota and run the same command again",
    errno.EROFS: WRITABLE_FOLDER,
    errno.EACCES: f"{WRITABLE_FOLDER}, or fix the permissions",
    errno.EPERM: WRITABLE_FOLDER,
    errno.ENOTDIR: "a part of the path is a file, not a folder: " + WRITABLE_FOLDER,
}


def fail_if_refused(err: BaseException) -> None:
    """Exit with one error line if the file system refused a file (disk full, read-only, no
    permission), be it ``err`` or the ``OSError`` that caused it; return for anything else."""
    refusal = err if isinstance(err, OSError) else err.__cause__
    fix = FILE_SYSTEM_FIXES.get(refusal.errno) if isinstance(refusal, OSError) else None
    if fix is not None:
        where = f" ({refusal.filename})" if refusal.filename else ""
        fail(f"{os.strerror(refusal.errno)}{where}; {fix}")


def user_errors(task: Callable[[DictConfig], Any]) -> Callable[[DictConfig], Any]:
    """Turn a ``KeyinError``, a bad value caught while instantiating or a refused write into one
    error line."""

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
        except OSError as err:
            fail_if_refused(err)
            raise

    return wrapper


def unknown_key_message(err: ConfigAttributeError | ConfigKeyError, hint: str) -> str:
    """``a.b.typo=1``: name the key, the closest existing one (or all of them) and ``+key=``; a
    method choice given where keyin 0.1 kept it: where it lives now."""
    moved = moved_key_message(err.full_key)
    if moved is not None:
        return moved
    parent = err.full_key.rpartition(".")[0]
    keys = [str(k) for k in (err.parent_node or {}) if k != "hydra"]
    close = difflib.get_close_matches(str(err.key), keys, n=1)
    prefix = f"{parent}." if parent else ""
    known = f"did you mean {prefix}{close[0]}?" if close else f"known keys: {', '.join(keys)}"
    return f"unknown config key {err.full_key} ({known}); {hint[0].lower()}{hint[1:]}"


def hydra_message(err: Exception) -> str:
    """Hydra's multi-line message of a bad option, key or override as one line."""
    cause = err.__cause__
    lines = str(err).partition("Config search path:")[0].splitlines()
    if isinstance(cause, (ConfigAttributeError, ConfigKeyError)) and cause.full_key and len(lines) > 1:
        return unknown_key_message(cause, lines[1])
    parts: list[str] = []
    for line in lines:
        if line.startswith("\t") and parts:  # an option listed under "Available options in ...:"
            parts[-1] += (" " if parts[-1].endswith(":") else ", ") + line.strip()
        elif line.strip():
            parts.append(line.strip().rstrip("."))
    return "; ".join(parts)


def help_without_choice(message: str, program: str, argv: list[str]) -> str | None:
    """What ``--help`` prints where the config cannot compose without a choice (``keyin-reproduce --help``, no
    ``table=``): Hydra composes the config to show it, so it names the choice and how to see the help; None where
    ``argv`` asks no help or ``message`` (:func:`hydra_message`) is another error."""
    group, _, options = message.partition("You must specify '")[2].partition("'")
    if not group or not {"--help", "-h"} & set(argv):
        return None
    options = options.partition("Available options:")[2].strip()
    return (f"{program} composes its config from {group}=<option> (one of: {options}); its help shows that config: "
            f"{program} {group}=<option> --help")


@contextlib.contextmanager
def hydra_raises() -> Iterator[None]:
    """Let Hydra raise its errors (``HYDRA_FULL_ERROR=1``) instead of printing them and exiting 1."""
    previous = os.environ.get("HYDRA_FULL_ERROR")
    os.environ["HYDRA_FULL_ERROR"] = "1"
    try:
        yield
    finally:
        if previous is None:
            os.environ.pop("HYDRA_FULL_ERROR", None)
        else:
            os.environ["HYDRA_FULL_ERROR"] = previous


def keyin_main(config_name: str) -> Callable[[Callable[[DictConfig], Any]], Callable[[], None]]:
    """``hydra.main`` on ``conf/<config_name>.yaml``, where a bad config group option, an unknown
    key, an unparsable override or a run dir that cannot be created gives one ``error:`` line and
    exit status 2, like the checks of the task itself."""

    def decorate(task: Callable[[DictConfig], Any]) -> Callable[[], None]:
        @functools.wraps(task)
        def configured(cfg: DictConfig) -> Any:
            show_library_info(bool(cfg.get("verbose", False)))
            return objective(task(cfg), cfg.get("objective"))

        hydra_main = hydra.main(config_path=f"pkg://{CONFIG_MODULE}", config_name=config_name, version_base="1.3")(configured)

        @functools.wraps(task)
        def main() -> None:
            quiet_expected_library_output()
            with hydra_raises():
                try:
                    hydra_main()
                except (ConfigCompositionException, OverrideParseException) as err:
                    usage = help_without_choice(hydra_message(err), f"keyin-{config_name}", sys.argv[1:])
                    if usage is None:
                        fail(hydra_message(err))
                    print(usage)
                except (OSError, ValueError) as err:  # Hydra creating the run dir or its log file
                    fail_if_refused(err)
                    raise

        return main

    return decorate


def objective(result: Any, key: str | None) -> Any:
    """What a job returns to Hydra's sweeper: ``result[key]`` (its metrics' ``objective``, e.g. the
    validation F1 an Optuna sweep maximises) as a float, None where the job has no such value; the
    result itself where the config names no objective."""
    if key is None or not isinstance(result, Mapping):
        return result
    value = result.get(key)
    return None if value is None else float(value)


def run_dir() -> Path:
    """The Hydra output dir of the current job."""
    return Path(HydraConfig.get().runtime.output_dir)


def config_choice(group: str) -> str | None:
    """The option chosen for a config group in the current job (e.g. ``scale`` → ``cpu``)."""
    return HydraConfig.get().runtime.choices.get(group)


def config_choices() -> dict[str, str]:
    """The option chosen for every config group of the current job but Hydra's own (``{"backbone": "ours",
    "scale": "cpu", ...}``): what a config's values alone do not name."""
    choices = HydraConfig.get().runtime.choices.items()
    return {group: choice for group, choice in choices if choice is not None and not group.startswith("hydra")}


def finished_metrics(folder: Path) -> dict[str, Any] | None:
    """A finished job's ``metrics.json`` (printed as its last line, as the job did), or None if it has none."""
    finished = Path(folder) / "metrics.json"
    if not finished.is_file():
        return None
    metrics = json.loads(finished.read_text())
    print(f"{folder} finished earlier; skipped (delete its metrics.json to run it again)")
    print(json.dumps(metrics, sort_keys=True))
    return metrics


def cpu_name() -> str:
    """The CPU's model name (``/proc/cpuinfo`` on Linux), else what :mod:`platform` knows."""
    with contextlib.suppress(OSError):
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    return platform.processor() or platform.machine()


def machine() -> dict[str, Any]:
    """What a job's wall times were measured on: the CPU, its logical CPUs, torch's threads and
    version, and the GPU where one is used."""
    import torch

    return {
        "cpu": cpu_name(),
        "cpus": os.cpu_count(),
        "torch_threads": torch.get_num_threads(),
        "torch": torch.__version__,
        "gpu": torch.cuda.get_device_name(0) if torch.cuda.is_available() else None,
    }


def write_metrics(metrics: Mapping[str, Any], folder: Path) -> Path:
    """Write ``metrics.json`` atomically, with the keyin version that wrote it and the machine it ran
    on (:func:`machine`), and print the metrics as the last line of output."""
    metrics = {**metrics, "keyin_version": __version__, "machine": machine()}
    path = Path(folder) / "metrics.json"
    atomic_write_text(path, json.dumps(dict(metrics), indent=1, sort_keys=True))
    print(json.dumps(dict(metrics), sort_keys=True))
    return path
