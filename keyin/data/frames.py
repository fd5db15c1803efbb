"""Stored frames to the model's frames: value checks, the frame stride, centre crop, resize, channels.

Values: uint8 (and other integer) frames are 0-255, bool frames 0/1, float frames lie in [0, 1].
Integer frames whose largest value is 1 are refused, since they are almost surely 0/1 images that
would look black, unless ``binary`` says they are (then 0/1 becomes 0/255). Frames that are one
value throughout are blank. These rules are shared by keyin-import and keyin-discover (videos) and
by every reader of keyin's HDF5 shards (:func:`keyin.data.hdf5.check_frame_values`); each names its
own fix.
"""

from __future__ import annotations

from typing import Iterable

import numpy as np
from PIL import Image

from keyin.errors import DatasetFormatError

CHANNELS = (1, 3)  # grey or RGB; a fourth (alpha) channel is dropped
# How videos of 0/1 frames are fixed (keyin-import and keyin-discover have binary=)
VIDEO_ZERO_ONE_FIX = "store them as 0/255 (frames * 255), as float in [0, 1], or pass binary=true to scale 0/1 to 0/255"
# The usual cause of blank frames and its fix
BLANK_FIX = "float frames in [0, 1] cast to uint8 become 0: store np.round(frames * 255).astype(np.uint8) instead"


def prepare_video(
    frames: Iterable[np.ndarray], where: str, image_size: int, channels: int, frame_stride: int, binary: bool = False
) -> tuple[np.ndarray, int, tuple[int, int, int]]:
    """Every ``frame_stride``-th frame, checked and fitted to the model.

    Args:
        frames: the video's (H, W, C) frames as stored, C in 1, 3, 4.
        where: how errors name the video.
    Returns:
        kept frames uint8 (ceil(T / frame_stride), image_size, image_size, channels), T, the
        number of frames the video had, and the (H, W, C) of its frames as stored.
    Raises:
        DatasetFormatError: no frames, a frame of another shape or kind, values out of range, 0/1 frames.
    """
    kept, count, high, dtype, shape = [], 0, 0, None, (0, 0, 0)
    for count, frame in enumerate(frames, start=1):
        frame = np.asarray(frame)
        if frame.ndim != 3 or frame.shape[-1] not in (1, 3, 4):
            raise DatasetFormatError(
                f"{where}: a frame has shape {frame.shape}; frames are (H, W, C) with C = 1 (grey), 3 (RGB) "
                f"or 4 (RGBA), so videos are (T, H, W, C) (grey ones need their channel axis: frames[..., None])"
            )
        dtype, shape = frame.dtype, frame.shape
        if (count - 1) % frame_stride:
            continue
        frame, frame_high = as_uint8(frame, where, binary)
        high = max(high, frame_high)
        kept.append(fit_frame(frame, image_size, channels))
    if count == 0:
        raise DatasetFormatError(f"{where} has zero frames; remove it from the source or pass a video with frames")
    if not binary:
        check_zero_one(dtype, high, where, VIDEO_ZERO_ONE_FIX)
    return np.stack(kept), count, shape


def check_zero_one(dtype: np.dtype, high: int, where: str, fix: str) -> None:
    """Refuse integer frames whose largest value ``high`` is 1: 0/1 images, black on the 0-255 scale.

    Args:
        dtype: the frames' dtype as stored.
        where: how the error names the frames.
        fix: what the error tells to do (it depends on who reads the frames).
    """
    if np.issubdtype(dtype, np.integer) and high == 1:
        raise DatasetFormatError(
            f"{where} holds {dtype} frames whose largest value is 1: 0/1 images look black on keyin's 0-255 scale; "
            f"{fix}"
        )


def is_blank(frames: np.ndarray) -> bool:
    """Whether ``frames`` (a clip or a video, any shape) are one value throughout: they show nothing."""
    return bool(frames.min() == frames.max())


def as_uint8(frame: np.ndarray, where: str, binary: bool) -> tuple[np.ndarray, int]:
    """(H, W, C) uint8 0-255 and the largest stored value (integer frames; 0 for others)."""
    if frame.dtype == bool:
        return frame.astype(np.uint8) * 255, 0
    if np.issubdtype(frame.dtype, np.floating):
        low, high = float(frame.min()), float(frame.max())
        if not (np.isfinite(low) and np.isfinite(high)) or low < 0 or high > 1:
            raise DatasetFormatError(
                f"{where}: float frames must lie in [0, 1], but a frame holds values in [{low:g}, {high:g}]; divide 0-255 "
                f"frames by 255 (or store them as uint8)"
            )
        return np.round(frame * 255).astype(np.uint8), 0
    if not np.issubdtype(frame.dtype, np.integer):
        raise DatasetFormatError(f"{where}: frames of dtype {frame.dtype}; store them as uint8 0-255 or float in [0, 1]")
    low, high = int(frame.min()), int(frame.max())
    top = 1 if binary else 255
    if low < 0 or high > top:
        fix = "drop binary=true" if binary else "store them as uint8 0-255 (16-bit frames: frames // 257)"
        raise DatasetFormatError(f"{where}: integer frames must lie in 0-{top}, but a frame holds values in [{low}, {high}]; {fix}")
    frame = frame.astype(np.uint8)
    return (frame * 255 if binary else frame), high


def fit_frame(frame: np.ndarray, image_size: int, channels: int) -> np.ndarray:
    """(H, W, C) uint8 → (image_size, image_size, channels): the centred square, resized (bilinear,
    antialiased), grey (ITU-R 601 luma) or RGB."""
    if channels not in CHANNELS:
        raise ValueError(f"channels must be 1 or 3, got {channels}")
    image = Image.fromarray(frame[..., 0] if frame.shape[-1] == 1 else frame)
    image = image.convert("L" if channels == 1 else "RGB")
    side = min(image.size)
    left, top = (image.width - side) // 2, (image.height - side) // 2
    image = image.crop((left, top, left + side, top + side))
    if side != image_size:
        image = image.resize((image_size, image_size), Image.Resampling.BILINEAR)
    return np.asarray(image).reshape(image_size, image_size, channels)


def fit_note(stored_shape: tuple[int, int, int], image_size: int, channels: int) -> str | None:
    """What :func:`fit_frame` does to frames of ``stored_shape`` (H, W, C), or None if they are the
    model's already, e.g. ``240x320 RGB frames are centre-cropped to 240x240 and resized to 64x64``."""
    height, width, stored = stored_shape
    kind = lambda c: "grey" if c == 1 else "RGB"  # noqa: E731  (a fourth, alpha channel is dropped)
    steps = []
    if height != width:
        steps.append(f"centre-cropped to {min(height, width)}x{min(height, width)}")
    if min(height, width) != image_size:
        steps.append(f"resized to {image_size}x{image_size}")
    if kind(stored) != kind(channels):
        steps.append(f"made {kind(channels)}")
    if not steps:
        return None
    done = steps[0] if len(steps) == 1 else f"{', '.join(steps[:-1])} and {steps[-1]}"
    return f"{height}x{width} {kind(stored)} frames are {done}"
