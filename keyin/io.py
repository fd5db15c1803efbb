"""Generic file utilities: SHA-256 checksums, atomic writes through a temporary name and a rename
(of a file, or of a whole folder), the removal of the temporaries that killed writers left behind,
and JSON-lines files that grow a whole line at a time.

A file or folder being written is named ``.<name>.tmp-<pid>`` beside its destination until its
rename, so a reader sees it whole or not at all, and a later run knows from the PID whether its
writer is gone.
A JSON-lines file gets each line in one ``write`` (flushed and fsynced), so a killed writer leaves at
most one partial last line, without a newline, which :func:`read_json_lines` tells apart.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
from pathlib import Path
from typing import Any, Mapping

from keyin.errors import DatasetFormatError

TEMPORARY_TAG = ".tmp-"  # a file being written is named .<name>.tmp-<pid> until its rename


def sha256_of(path: Path) -> str:
    """Hex SHA-256 of a file, read in 1 MiB blocks."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def temporary_path(path: Path) -> Path:
    """Where ``path`` is written before the rename: a hidden name in the same folder with our PID."""
    return path.with_name(f".{path.name}{TEMPORARY_TAG}{os.getpid()}")


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file, fsync and a rename.

    ``path`` either keeps its old content or gets all of ``data``; on an error (a full disk) the
    temporary file is removed. Only a killed process leaves one, which
    :func:`remove_stale_temporaries` clears on the next run.
    """
    path = Path(path)
    tmp = temporary_path(path)
    try:
        with open(tmp, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(tmp, path)
    except OSError as err:
        if err.filename is None:  # a failed write() names no file: name the one being written
            raise OSError(err.errno, err.strerror, str(path)) from err
        raise
    finally:
        tmp.unlink(missing_ok=True)


def atomic_write_text(path: Path, text: str) -> None:
    """Write ``text`` (UTF-8) to ``path`` atomically (see :func:`atomic_write_bytes`)."""
    atomic_write_bytes(path, text.encode("utf-8"))


def process_alive(pid: int) -> bool:
    """Whether a process with this id exists (on this machine)."""
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def remove_stale_temporaries(folder: Path) -> list[Path]:
    """Delete the temporary files and folders that killed writers left in ``folder``; returns them.

    A temporary whose writer (the PID in its name) still runs is kept.
    """
    folder, removed = Path(folder), []
    for tmp in folder.glob(f".*{TEMPORARY_TAG}*") if folder.is_dir() else ():
        pid = tmp.name.rpartition(TEMPORARY_TAG)[2]
        if pid.isdigit() and not process_alive(int(pid)):
            if tmp.is_dir() and not tmp.is_symlink():
                shutil.rmtree(tmp, ignore_errors=True)
            else:
                tmp.unlink(missing_ok=True)
            removed.append(tmp)
    return removed


def replace_folder(complete: Path, destination: Path) -> None:
    """Put the finished folder ``complete`` (written under ``temporary_path(destination)``) in place of
    ``destination`` by renames, so a reader finds the old folder or the new one, never a mix; a
    folder that was there is moved to a temporary name first and deleted after."""
    complete, destination = Path(complete), Path(destination)
    old = temporary_path(destination.with_name(f"{destination.name}.old"))
    if destination.exists():
        os.replace(destination, old)
    os.replace(complete, destination)
    shutil.rmtree(old, ignore_errors=True)


def append_json_line(path: Path, record: Mapping[str, Any]) -> None:
    """Append ``record`` to ``path`` as one JSON line (sorted keys), durably."""
    with open(path, "a", encoding="utf-8") as handle:
        handle.write(json.dumps(dict(record), sort_keys=True) + "\n")
        handle.flush()
        os.fsync(handle.fileno())


def read_json_lines(path: Path) -> tuple[list[dict[str, Any]], str, str]:
    """The records of a JSON-lines file's complete lines, those lines' text, and a partial last line
    ('' if none); no file gives none. The file is not touched.

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
                f"have its entry written again"
            )
        records.append(record)
    return records, complete, partial
