"""Simulated file-system faults for the reliability tests: a disk that fills up, a read-only folder."""

from __future__ import annotations

import errno
import os
from pathlib import Path
from types import ModuleType
from typing import Callable

import pytest


def refuse(code: int, path: object = None) -> OSError:
    """The ``OSError`` the kernel would raise with ``code`` (and ``path``)."""
    return OSError(code, os.strerror(code), *(() if path is None else (str(path),)))


def fill_disk_on(monkeypatch: pytest.MonkeyPatch, module: ModuleType, is_full: Callable[[Path], bool]) -> None:
    """Make the disk full from the first ``module.atomic_write_bytes(path, ...)`` with ``is_full(path)``
    on: that write creates its temporary file and writes, then ``fsync`` fails with ENOSPC."""
    real_write = module.atomic_write_bytes

    def disk_full(fd: int) -> None:
        raise refuse(errno.ENOSPC)

    def write(path: Path, data: bytes) -> None:
        if is_full(Path(path)):
            monkeypatch.setattr(os, "fsync", disk_full)
        real_write(path, data)

    monkeypatch.setattr(module, "atomic_write_bytes", write)


def make_read_only(monkeypatch: pytest.MonkeyPatch, folder: Path) -> None:
    """``folder`` behaves as on a read-only file system: creating anything in it fails with EROFS
    (chmod would not do: the tests may run as root)."""
    real_mkdir = os.mkdir

    def mkdir(path, mode=0o777, **kwargs):
        if Path(path).is_relative_to(folder):
            raise refuse(errno.EROFS, path)
        return real_mkdir(path, mode, **kwargs)

    monkeypatch.setattr(os, "mkdir", mkdir)
