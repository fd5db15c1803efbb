"""The videos of an import source, found by name and decoded one frame at a time.

A source is one of:

* a video file (``.mp4 .avi .webm .gif .mov .mkv .m4v``), decoded by PyAV (FFmpeg inside its wheel);
* a folder of image frames (``.png .jpg .jpeg``): one video, its frames in name order;
* an array file: ``.npy`` holding (T, H, W, C) or (n, T, H, W, C), ``.npz`` one or more such arrays;
* a robomimic-style HDF5 file (``.hdf5 .h5``): one video per ``data/demo_<i>/obs/<camera key>``;
* a LeRobot v2 dataset folder (``meta/info.json``, one mp4 per episode and camera under ``videos/``):
  one video per episode of one camera;
* a folder of any of these, of frame folders and of LeRobot folders: each entry's videos (one level
  deep; hidden entries and files of other kinds are passed over).

Names are in natural order (``frame2`` before ``frame10``, ``demo_2`` before ``demo_10``). Each video
has an id that names it in label files and in the manifest: its file or folder name, then
``[key]`` for an ``.npz`` array or a robomimic demo and ``[i]`` for the i-th video of an
(n, T, H, W, C) array, e.g. ``clips.npz[frames][3]``, ``demos.hdf5[demo_0]``; a LeRobot episode is
``<folder name>[episode_<index>]``.

Frames are yielded as stored, (H, W, C) arrays of any dtype; :mod:`keyin.data.frames` checks their
values and fits them to the model.
"""

from __future__ import annotations

import json
import re
import zipfile
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Iterator

import av
import h5py
import numpy as np
from PIL import Image, UnidentifiedImageError

from keyin.errors import DatasetFormatError

VIDEO_SUFFIXES = (".mp4", ".avi", ".webm", ".gif", ".mov", ".mkv", ".m4v")
IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg")
ARRAY_SUFFIXES = (".npy", ".npz")
HDF5_SUFFIXES = (".hdf5", ".h5")
ROBOMIMIC_CAMERA = "agentview_image"  # the camera of a robomimic file when camera_key is null
LEROBOT_INFO = Path("meta") / "info.json"
LEROBOT_KEYS = ("fps", "chunks_size", "video_path", "features")  # what meta/info.json must hold for keyin
GREY_MODES, COLOUR_MODES = ("1", "L", "LA"), ("RGB", "RGBA", "P", "PA", "CMYK", "YCbCr")


@dataclass(frozen=True)
class Video:
    """One video of a source: ``frames`` yields its (H, W, C) frames as stored, once."""

    id: str
    path: Path
    frames: Iterable[np.ndarray]
    fps: float | None = None
    camera: str | None = None  # the camera read, for a robomimic demo or a LeRobot episode

    @property
    def where(self) -> str:
        """How an error names the video: its file, and its id within the file where that differs."""
        return str(self.path) if self.id == self.path.name else f"{self.path} (video {self.id})"


def natural_key(name: str) -> list:
    """Sort key comparing the digit runs of a name as numbers."""
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", name)]


def by_name(paths: Iterable[Path]) -> list[Path]:
    return sorted(paths, key=lambda path: natural_key(path.name))


def suffix(path: Path) -> str:
    return path.suffix.lower()


def visible(folder: Path) -> Iterator[Path]:
    """A folder's entries but hidden ones (``.DS_Store``, ``._frame1.png``, a killed import's folder)."""
    return (path for path in folder.iterdir() if not path.name.startswith("."))


def image_files(folder: Path) -> list[Path]:
    return by_name(p for p in visible(folder) if p.is_file() and suffix(p) in IMAGE_SUFFIXES)


def find_videos(source: Path, camera_key: str | None, key: str = "source") -> Iterator[Video]:
    """Every video of ``source`` (see the module docstring), in natural name order; ``camera_key``
    picks the camera of a robomimic file or LeRobot folder (None: ``agentview_image``, or a LeRobot
    folder's only camera); ``key`` is the setting that named the source, for the errors.

    Raises:
        DatasetFormatError: the source does not exist, holds no video, or mixes frames and videos.
    """
    source = Path(source)
    if not source.exists():
        raise DatasetFormatError(f"{key} {source} does not exist; pass {key}=<a video file, an array or "
                                 f"robomimic file, a LeRobot v2 folder, or a folder of videos or of image frames>")
    if source.is_file():
        yield from file_videos(source, camera_key)
        return
    if is_lerobot(source):
        yield from lerobot_videos(source, camera_key, key)
        return
    frames = image_files(source)
    entries = by_name(p for p in visible(source) if p.is_dir() and (image_files(p) or is_lerobot(p)) or is_media(p))
    if frames and entries:
        raise DatasetFormatError(
            f"{source} holds both image frames ({frames[0].name}, ...) and videos ({entries[0].name}, ...); "
            f"put the frames of each video in a folder of their own"
        )
    if frames:
        yield frame_folder(source, frames)
        return
    if not entries:
        known = ", ".join(VIDEO_SUFFIXES + IMAGE_SUFFIXES + ARRAY_SUFFIXES + HDF5_SUFFIXES)
        raise DatasetFormatError(
            f"{source} holds no videos, frames, array files ({known}) or LeRobot folders; pass another {key}="
        )
    for entry in entries:
        if is_lerobot(entry):
            yield from lerobot_videos(entry, camera_key, key)
        elif entry.is_dir():
            yield frame_folder(entry, image_files(entry))
        else:
            yield from file_videos(entry, camera_key)


def is_lerobot(folder: Path) -> bool:
    return (folder / LEROBOT_INFO).is_file()


def is_media(path: Path) -> bool:
    return path.is_file() and suffix(path) in VIDEO_SUFFIXES + ARRAY_SUFFIXES + HDF5_SUFFIXES


def file_videos(path: Path, camera_key: str | None) -> Iterator[Video]:
    """The videos of one file, by its suffix."""
    kind = suffix(path)
    if kind in VIDEO_SUFFIXES:
        yield video_file(path)
    elif kind in ARRAY_SUFFIXES:
        yield from array_videos(path)
    elif kind in HDF5_SUFFIXES:
        yield from robomimic_videos(path, camera_key)
    else:
        raise DatasetFormatError(
            f"{path} is not a file keyin imports (videos {', '.join(VIDEO_SUFFIXES)}; arrays .npy/.npz; "
            f"robomimic .hdf5); convert it or pass a folder of image frames"
        )


def video_file(path: Path) -> Video:
    """A video file; its frame rate is the stream's average rate."""
    try:
        with av.open(str(path)) as container:
            if not container.streams.video:
                raise DatasetFormatError(f"{path} has no video stream; pass a file with video in it")
            rate = container.streams.video[0].average_rate
    except av.error.FFmpegError as err:
        raise unreadable_video(path, err) from None
    return Video(path.name, path, decoded_frames(path), float(rate) if rate else None)


def unreadable_video(path: Path, err: Exception) -> DatasetFormatError:
    return DatasetFormatError(
        f"{path} is not a readable video ({err}); it is corrupt or not a video: re-encode it (e.g. "
        f"`ffmpeg -i {path.name} fixed.mp4`) or remove it from the source"
    )


def decoded_frames(path: Path) -> Iterator[np.ndarray]:
    """The (H, W, 3) uint8 RGB frames of a video file's first video stream."""
    try:
        with av.open(str(path)) as container:
            for frame in container.decode(container.streams.video[0]):
                yield frame.to_ndarray(format="rgb24")
    except av.error.FFmpegError as err:
        raise unreadable_video(path, err) from None


def frame_folder(folder: Path, files: list[Path]) -> Video:
    return Video(folder.name, folder, image_frames(folder, files))


def image_frames(folder: Path, files: list[Path]) -> Iterator[np.ndarray]:
    """The frames of a folder of images, (H, W, 1) grey or (H, W, 3) RGB; every image one size and kind."""
    first = None
    for file in files:
        try:
            with Image.open(file) as image:
                image.load()
        except (UnidentifiedImageError, OSError) as err:
            raise DatasetFormatError(f"{file} is not a readable image ({err}); replace or remove it") from None
        if image.mode not in GREY_MODES + COLOUR_MODES:
            raise DatasetFormatError(
                f"{file} is a {image.mode!r} image (16-bit or float); save the frames as 8-bit grey or RGB"
            )
        kind = (image.size, image.mode in GREY_MODES)
        if first is None:
            first = (file, kind)
        elif kind != first[1]:
            raise DatasetFormatError(
                f"{folder} mixes image sizes or kinds: {first[0].name} is {describe(*first[1])}, {file.name} is "
                f"{describe(*kind)}; give every frame of a video one size and kind (or move the odd ones out)"
            )
        grey = image.convert("L") if kind[1] else image.convert("RGB")
        yield np.asarray(grey).reshape(grey.height, grey.width, -1)


def describe(size: tuple[int, int], grey: bool) -> str:
    return f"{size[0]}x{size[1]} {'grey' if grey else 'colour'}"


def array_videos(path: Path) -> Iterator[Video]:
    """The videos of an ``.npy`` or ``.npz`` file: (T, H, W, C) is one, (n, T, H, W, C) n."""
    try:
        if suffix(path) == ".npy":
            arrays = [(path.name, np.load(path, mmap_mode="r", allow_pickle=False))]
        else:
            with np.load(path, allow_pickle=False) as archive:
                arrays = [(f"{path.name}[{key}]", archive[key]) for key in sorted(archive.files, key=natural_key)]
    except (ValueError, OSError, EOFError, zipfile.BadZipFile) as err:
        raise DatasetFormatError(
            f"{path} is not a readable {suffix(path)} file ({err}); write the frames with numpy.save / "
            f"numpy.savez (no pickled objects)"
        ) from None
    for name, array in arrays:
        if array.ndim == 4:
            yield Video(name, path, array)
        elif array.ndim == 5:
            yield from (Video(f"{name}[{i}]", path, video) for i, video in enumerate(array))
        else:
            raise DatasetFormatError(
                f"{path}: array {name} has shape {array.shape}; frames are (T, H, W, C) or (n, T, H, W, C) "
                f"(grey frames need their channel axis: frames[..., None])"
            )


def robomimic_videos(path: Path, camera_key: str | None) -> Iterator[Video]:
    """One video per ``data/demo_<i>/obs/<camera_key>`` of a robomimic-style HDF5 file."""
    camera_key = camera_key or ROBOMIMIC_CAMERA
    try:
        handle = h5py.File(path, "r")
    except OSError as err:
        raise DatasetFormatError(f"{path} is not a readable HDF5 file ({err}); it is truncated or corrupt") from None
    with handle:
        data = handle.get("data")
        demos = sorted(data, key=natural_key) if isinstance(data, h5py.Group) else []
        if not demos:
            raise DatasetFormatError(
                f"{path} has no data/demo_* groups; a robomimic-style file holds its frames in "
                f"data/demo_<i>/obs/<camera key>"
            )
        for demo in demos:
            obs = data[demo].get("obs")
            if not isinstance(obs, h5py.Group) or not isinstance(obs.get(camera_key), h5py.Dataset):
                cameras = sorted(k for k, v in (obs or {}).items() if isinstance(v, h5py.Dataset) and v.ndim == 4)
                raise DatasetFormatError(
                    f"{path}: data/{demo}/obs has no '{camera_key}'; set camera_key= to the camera to "
                    f"import ({', '.join(cameras) or 'this demo has no (T, H, W, C) observation'})"
                )
            yield Video(f"{path.name}[{demo}]", path, obs[camera_key][()], camera=camera_key)


def lerobot_videos(root: Path, camera_key: str | None, key: str = "source") -> Iterator[Video]:
    """One video per episode of a LeRobot v2 folder, the mp4 that ``meta/info.json``'s ``video_path``
    template names for the episode and camera; episodes from ``meta/episodes.jsonl`` (or
    ``total_episodes``), the frame rate from ``fps``. Every episode's file is checked before the first
    is decoded."""
    info = lerobot_info(root)
    camera = lerobot_camera(root, info, camera_key)
    episodes = lerobot_episodes(root, info)
    if not episodes:
        raise DatasetFormatError(f"{root} lists no episodes (meta/episodes.jsonl, total_episodes); pass another {key}=")
    paths = {index: root / lerobot_video_path(root, info, camera, index) for index in episodes}
    missing = [index for index, path in paths.items() if not path.is_file()]
    if missing:
        raise DatasetFormatError(
            f"{root}: {len(missing)} episode video(s) for camera {camera!r} do not exist, e.g. episode {missing[0]}'s "
            f"{paths[missing[0]]}; download the dataset's videos/ too, or drop those episodes from meta/episodes.jsonl"
        )
    for index, path in paths.items():
        yield Video(f"{root.name}[episode_{index}]", path, video_file(path).frames, float(info["fps"]), camera)


def lerobot_video_path(root: Path, info: dict, camera: str, index: int) -> str:
    """``video_path`` filled in for one episode and camera (episode_chunk = index // chunks_size)."""
    try:
        return info["video_path"].format(episode_chunk=index // info["chunks_size"], video_key=camera, episode_index=index)
    except (KeyError, IndexError, ValueError) as err:
        raise DatasetFormatError(
            f"{root / LEROBOT_INFO}: video_path {info['video_path']!r} is not a LeRobot v2 template ({err!r}); "
            f"it names {{episode_chunk}}, {{video_key}} and {{episode_index}}"
        ) from None


def lerobot_info(root: Path) -> dict:
    """``meta/info.json`` of a LeRobot folder, checked to be the v2 layout (one mp4 per episode) with
    the fields keyin reads well formed."""
    path = root / LEROBOT_INFO
    try:
        info = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as err:
        raise DatasetFormatError(f"{path} is not readable JSON ({err}); it is truncated or corrupt") from None
    version = str(info.get("codebase_version", "")) if isinstance(info, dict) else ""
    if not version.startswith("v2"):
        raise DatasetFormatError(
            f"{path} says codebase_version {version or 'nothing'}; keyin reads LeRobot's v2.0/v2.1 layout "
            f"(one mp4 per episode and camera; v3.0 packs many episodes into one file): download the dataset's "
            f"v2.1 revision, or export the episodes as mp4 files and pass their folder"
        )
    missing = [key for key in LEROBOT_KEYS if key not in info]
    if missing:
        raise DatasetFormatError(f"{path} has no {', '.join(missing)}; a LeRobot v2 info.json holds {', '.join(LEROBOT_KEYS)}")
    malformed = [f"{name}={info[name]!r} (a whole number >= {least})"
                 for name, least in (("chunks_size", 1), ("total_episodes", 0))
                 if name in info and not (is_number(info[name], int) and info[name] >= least)]
    if not (is_number(info["fps"], (int, float)) and info["fps"] > 0):
        malformed.append(f"fps={info['fps']!r} (a number > 0)")
    if not isinstance(info["video_path"], str):
        malformed.append(f"video_path={info['video_path']!r} (a path template)")
    if not isinstance(info["features"], dict):
        malformed.append(f"features of type {type(info['features']).__name__} (an object of feature name: description)")
    if malformed:
        raise DatasetFormatError(f"{path} holds {'; '.join(malformed)}; fix the file (LeRobot v2 writes these fields)")
    return info


def is_number(value: object, kinds: type | tuple[type, ...]) -> bool:
    """``value`` is of ``kinds`` and not a bool (JSON's true is no count)."""
    return isinstance(value, kinds) and not isinstance(value, bool)


def lerobot_camera(root: Path, info: dict, camera_key: str | None) -> str:
    """The camera to import: ``camera_key``, or the folder's only video feature when it is None."""
    cameras = sorted(key for key, feature in info["features"].items()
                     if isinstance(feature, dict) and feature.get("dtype") == "video")
    if not cameras:
        raise DatasetFormatError(
            f"{root / LEROBOT_INFO} lists no video features (dtype 'video'); keyin imports a LeRobot dataset's "
            f"camera videos, not frames stored in its parquet files"
        )
    if camera_key in cameras or (camera_key is None and len(cameras) == 1):
        return camera_key or cameras[0]
    asked = f"has no camera {camera_key!r}" if camera_key else f"has {len(cameras)} cameras"
    choices = ", ".join(f"camera_key={camera}" for camera in cameras)
    raise DatasetFormatError(f"{root} {asked}; pick one: {choices}")


def lerobot_episodes(root: Path, info: dict) -> list[int]:
    """The episode indices of ``meta/episodes.jsonl``, or 0 … total_episodes − 1 where it is missing.

    Raises:
        DatasetFormatError: a line without an integer ``episode_index``, or one index listed twice.
    """
    path = root / "meta" / "episodes.jsonl"
    if not path.is_file():
        return list(range(info.get("total_episodes", 0)))
    try:
        indices = [int(json.loads(line)["episode_index"]) for line in path.read_text().splitlines() if line.strip()]
    except (ValueError, KeyError, TypeError) as err:
        raise DatasetFormatError(
            f"{path}: a line is not a JSON object with an integer episode_index ({err!r}); fix or remove the line"
        ) from None
    twice = sorted(index for index, count in Counter(indices).items() if count > 1)
    if twice:
        raise DatasetFormatError(f"{path} lists episode {twice[0]} more than once; keep one line per episode")
    return sorted(indices)
