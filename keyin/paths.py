"""File names that come from user files (a manifest, a metrics.json) stay inside their folder."""

from __future__ import annotations

from pathlib import Path

from keyin.errors import UnsafePathError


def inside(folder: Path, name: str, source: str) -> Path:
    """``folder / name``, refused unless it resolves to a file strictly inside ``folder``.

    Args:
        folder: the folder the file must stay in.
        name: a relative name read from ``source`` (no ``..`` out of the folder, no absolute path,
            no symlink pointing elsewhere).
        source: where the name came from, for the error message.
    """
    base = Path(folder).resolve()
    path = (base / str(name)).resolve()
    if path == base or not path.is_relative_to(base):
        raise UnsafePathError(
            f"{source} names the file {name!r}, which is outside {folder}; a keyin file only names "
            f"files in its own folder: regenerate or repair {source}"
        )
    return path
