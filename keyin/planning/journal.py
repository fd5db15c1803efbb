"""A run dir's record of finished tasks: ``tasks.jsonl``, one JSON object per line, and the settings
they were planned with (``plan.json``), so that the same command resumes where a killed run stopped.

A line is appended whole (one ``write`` of the line and its newline, flushed and fsynced) once its
task is finished; a killed writer can leave at most one partial last line, without a newline,
which :func:`read_journal` drops from the file before anything else is appended.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Mapping

from keyin.errors import ConfigError, DatasetFormatError
from keyin.io import atomic_write_text


def parse_journal(path: Path) -> tuple[list[dict[str, Any]], str, str]:
    """The records of the complete lines, those lines' text, and a partial last line ('' if none);
    the file is not touched (``keyin-report`` reads journals this way).

    Raises:
        DatasetFormatError: a complete line that is not a JSON object (the file was edited).
    """
    path = Path(path)
    if not path.is_file():
        return [], "", ""
    complete, _, partial = path.read_text(encoding="utf-8").rpartition("\n")
    records = []
    for number, line in enumerate(complete.splitlines() if complete else [], start=1):
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            record = None
        if not isinstance(record, dict):
            raise DatasetFormatError(
                f"{path} line {number} is not a JSON object (the file was edited); delete that line to "
                f"plan its task again"
            )
        records.append(record)
    return records, complete, partial


def read_journal(path: Path) -> tuple[list[dict[str, Any]], bool]:
    """The finished records and whether a partial last line was dropped: the file is rewritten
    without it, so the next line appended starts on a line of its own."""
    records, complete, partial = parse_journal(path)
    if partial:
        atomic_write_text(Path(path), complete + "\n" if complete else "")
    return records, bool(partial)


def append_record(path: Path, record: Mapping[str, Any]) -> None:
    """Append one record as a line, durably."""
    with open(path, "a", encoding="utf-8") as handle:
        handle.write(json.dumps(dict(record), sort_keys=True) + "\n")
        handle.flush()
        os.fsync(handle.fileno())


def flat(settings: Mapping[str, Any], prefix: str = "") -> dict[str, Any]:
    """Nested mappings as ``{"a.b": value}``."""
    out: dict[str, Any] = {}
    for key, value in settings.items():
        if isinstance(value, Mapping):
            out.update(flat(value, f"{prefix}{key}."))
        else:
            out[f"{prefix}{key}"] = value
    return out


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
    before, now = flat(json.loads(path.read_text())), flat(settings)
    changed = [key for key in sorted({*before, *now}) if before.get(key) != now.get(key)]
    if changed:
        differences = ", ".join(f"{key}={before.get(key)!r} (now {now.get(key)!r})" for key in changed)
        raise ConfigError(
            f"{folder} holds tasks planned with other settings: {differences}; resume with the same "
            f"overrides, or plan into a new run dir"
        )
