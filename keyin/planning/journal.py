"""A run dir's record of finished tasks: ``tasks.jsonl``, one JSON object per line, and the settings
they were planned with (``plan.json``), so that the same command resumes where a killed run stopped.

A line is appended whole (:func:`keyin.io.append_json_line`) once its task is finished; a killed
writer can leave at most one partial last line, without a newline, which :func:`read_journal` drops
from the file before anything else is appended.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Mapping

from keyin.errors import ConfigError
from keyin.io import atomic_write_text, read_json_lines


def read_journal(path: Path) -> tuple[list[dict[str, Any]], bool]:
    """The finished records and whether a partial last line was dropped: the file is rewritten
    without it, so the next line appended starts on a line of its own."""
    records, complete, partial = read_json_lines(path)
    if partial:
        atomic_write_text(Path(path), complete + "\n" if complete else "")
    return records, bool(partial)


def flat(settings: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested mappings as ``{"a.b": value}``."""
    out: dict[str, Any] = {}
    for key, value in settings.items():
        if isinstance(value, Mapping):
            out.update(flat(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


# Settings added since a run dir may have been claimed, at the value that plans as before.
ADDED_SINCE = {"planner.servo_observe": "state", "planner.model_seed": 0}


def claim_run_dir(folder: Path, settings: Mapping[str, Any]) -> None:
    """Record ``settings`` in ``folder/plan.json``, or check that they are the recorded ones.

    Raises:
        ConfigError: the run dir holds tasks planned with other settings.
    """
    path = Path(folder) / "plan.json"
    settings = json.loads(json.dumps(dict(settings)))  # tuples as lists, like the file
    if not path.is_file():
        atomic_write_text(path, json.dumps(settings, indent=1, sort_keys=True))
        return
    now = flat(settings)
    before = {**{key: value for key, value in ADDED_SINCE.items() if key in now}, **flat(json.loads(path.read_text()))}
    changed = [key for key in sorted({*before, *now}) if before.get(key) != now.get(key)]
    if changed:
        differences = ", ".join(f"{key}={before.get(key)!r} (now {now.get(key)!r})" for key in changed)
        raise ConfigError(
            f"{folder} holds tasks planned with other settings: {differences}; resume with the same "
            f"overrides, or plan into a new run dir"
        )
