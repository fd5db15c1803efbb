"""The sequence end of the information rule (docs/evaluation.md): where a clip that stops inside
the window ends, and the keyframe positions with that frame added."""

from __future__ import annotations

from collections.abc import Iterable, Sequence


def sequence_ends(lengths: Iterable[int], n_future: int) -> list[int | None]:
    """Per clip, its last valid future frame if the sequence ends inside the window (the rest is
    padding), else None: a clip that fills the window was cut there, and its last frame is no event."""
    return [length - 1 if 0 < length < n_future else None for length in lengths]


def with_ends(positions: Iterable[Iterable[int]], ends: Sequence[int | None]) -> list[list[int]]:
    """Per clip, the increasing positions with the clip's sequence end added (once)."""
    return [
        sorted({int(p) for p in row} | ({end} if end is not None else set()))
        for row, end in zip(positions, ends, strict=True)
    ]
