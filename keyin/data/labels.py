"""Keyframe labels of imported videos: original frame numbers per video id, from JSON or CSV.

* JSON: an object, video id → list of frame numbers: ``{"walk.mp4": [12, 40, 71]}``;
* CSV: a header ``video,frame`` and one row per keyframe: ``walk.mp4,12``.

Frame numbers count the original video's frames from 0, before any frame stride. Video ids are
those of :mod:`keyin.data.sources`; a video the file does not name has no keyframes.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Iterable

from keyin.errors import DatasetFormatError

Labels = dict[str, list[int]]


def read_labels(path: Path) -> Labels:
    """The labels of a ``.json`` or ``.csv`` file (see the module docstring).

    Raises:
        DatasetFormatError: a missing or malformed file, a frame that is not a whole number >= 0.
    """
    path = Path(path)
    if not path.is_file():
        raise DatasetFormatError(f"labels file {path} does not exist; pass labels=<a .json or .csv file> or drop labels=")
    if path.suffix.lower() == ".json":
        try:
            loaded = json.loads(path.read_text(encoding="utf-8"))
        except (json.JSONDecodeError, UnicodeDecodeError) as err:
            raise DatasetFormatError(f"{path} is not valid JSON ({err}); fix the file") from None
        if not isinstance(loaded, dict) or not all(isinstance(v, list) for v in loaded.values()):
            raise DatasetFormatError(f'{path} must hold an object of video id -> frame list, e.g. {{"a.mp4": [12, 40]}}')
        pairs = [(str(video), frame) for video, frames in loaded.items() for frame in frames]
    elif path.suffix.lower() == ".csv":
        with open(path, newline="", encoding="utf-8") as handle:
            reader = csv.DictReader(handle)
            if reader.fieldnames is None or not {"video", "frame"} <= set(reader.fieldnames):
                raise DatasetFormatError(f"{path} needs the header video,frame and one row per keyframe (a.mp4,12)")
            pairs = [(row["video"], row["frame"]) for row in reader]
    else:
        raise DatasetFormatError(f"labels file {path} is neither .json nor .csv; write it as one of them")
    labels: Labels = {}
    for video, frame in pairs:
        labels.setdefault(video, []).append(frame_number(frame, path, video))
    return labels


def frame_number(value: object, path: Path, video: str) -> int:
    """A label's frame as an int; a bool, a fraction, a negative number or text are refused."""
    if isinstance(value, str) and value.strip().isdigit():
        return int(value)
    if isinstance(value, int) and not isinstance(value, bool) and value >= 0:
        return value
    raise DatasetFormatError(f"{path}: video {video!r} has the keyframe {value!r}; frames are whole numbers >= 0")


def check_video_labels(labels: Labels, path: Path, video: str, where: str, n_frames: int) -> list[int]:
    """The labels of one video, each checked to be one of its ``n_frames`` frames."""
    frames = labels.get(video, [])
    past = [frame for frame in frames if frame >= n_frames]
    if past:
        raise DatasetFormatError(
            f"{path}: video {video!r} has keyframe {past[0]}, past its end: {where} has {n_frames} frames "
            f"(0-{n_frames - 1}); fix the label (frames count the original video from 0, before frame_stride)"
        )
    return frames


def check_known(labels: Labels, path: Path, videos: Iterable[str]) -> None:
    """Every video the labels name is one of the source's."""
    known = list(videos)
    unknown = sorted(set(labels) - set(known))
    if unknown:
        raise DatasetFormatError(
            f"{path} labels the video {unknown[0]!r}, which is not in the source (its videos: "
            f"{', '.join(known[:5])}{', ...' if len(known) > 5 else ''}); a video's id is its file or folder name, "
            f"with [key] and [i] for the videos inside an array or robomimic file"
        )
