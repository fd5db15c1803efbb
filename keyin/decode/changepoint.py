"""A change-point detector on the frames (the ruptures library's PELT): keyframes without a model.

The label-free baseline a user would try before training anything. Each clip's frames from K^0,
the last conditioning frame, to its last valid frame are a signal over time — the frames
themselves (``pixels``), their differences (``differences``: piecewise constant where the
intensities change at a constant rate) or the velocity of the centroid of what moved
(``centroid_velocity``: per channel the centre of ``|frame − background|``, the background being
the clip's median frame over time; piecewise constant where the objects move at constant
velocity, so it changes where one turns; a static background drops out);
PELT finds the segmentation of least summed segment cost plus
``penalty`` per change, exactly. A change that starts a new segment at extended index ``b`` (the
frame where the signal changes: for differences the frame at which the velocity turns) is future
position ``b − 1``.
"""

from __future__ import annotations

import numpy as np
import ruptures
from torch import Tensor

SIGNALS = ("pixels", "differences", "centroid_velocity")
COSTS = ("l1", "l2", "rbf")


def intensity_centroids(frames: np.ndarray) -> np.ndarray:
    """(T, 2·C) the intensity-weighted (row, column) centre of each channel of (T, C, H, W) frames,
    in pixels (a blank channel gives the image centre)."""
    _, _, height, width = frames.shape
    mass = frames.sum(axis=(2, 3)) + 1e-9  # (T, C)
    rows = (frames.sum(axis=3) * np.arange(height)).sum(axis=2) / mass
    cols = (frames.sum(axis=2) * np.arange(width)).sum(axis=2) / mass
    blank = frames.sum(axis=(2, 3)) == 0
    rows[blank], cols[blank] = (height - 1) / 2, (width - 1) / 2
    return np.concatenate([rows, cols], axis=1)


class ChangepointKeyframes:
    """At most ``n_keyframes`` change points of each clip (see module doc).

    Args:
        n_keyframes: M, the most keyframes kept (the earliest ones).
        n_cond: conditioning frames at the start of each clip.
        penalty: PELT's price per change point (chosen on validation clips:
            ``benchmarks/choose_changepoint_penalty.py``).
        signal: "pixels", "differences" or "centroid_velocity".
        cost: ruptures' segment model, "l1", "l2" or "rbf".
    """

    def __init__(
        self, n_keyframes: int, n_cond: int, penalty: float, signal: str = "centroid_velocity", cost: str = "l2"
    ) -> None:
        if signal not in SIGNALS:
            raise ValueError(f"signal must be one of {SIGNALS}, got {signal!r}")
        if cost not in COSTS:
            raise ValueError(f"cost must be one of {COSTS}, got {cost!r}")
        if penalty < 0:
            raise ValueError(f"penalty must be >= 0, got {penalty}")
        self.n_keyframes, self.n_cond, self.penalty, self.signal, self.cost = n_keyframes, n_cond, penalty, signal, cost

    def series(self, frames: np.ndarray) -> np.ndarray:
        """(T, D) signal of (length + 1, C, H, W) frames on the extended index."""
        frames = frames.astype(np.float64)
        if self.signal == "pixels":
            return frames.reshape(len(frames), -1)
        if self.signal == "differences":
            return np.diff(frames.reshape(len(frames), -1), axis=0)
        background = np.median(frames, axis=0, keepdims=True)
        return np.diff(intensity_centroids(np.abs(frames - background)), axis=0)

    def detector(self, frames: np.ndarray, length: int) -> ruptures.Pelt | None:
        """PELT fitted to one clip's frames (L, C, H, W) with ``length`` valid future frames (None
        for a clip too short to change)."""
        if length < 2:
            return None
        series = self.series(frames[self.n_cond - 1 : self.n_cond + length])
        return ruptures.Pelt(model=self.cost, min_size=1, jump=1).fit(series)

    def positions(self, detector: ruptures.Pelt | None, length: int, penalty: float | None = None) -> list[int]:
        """Keyframe positions of a fitted :meth:`detector` at ``penalty`` (default: the configured one)."""
        if detector is None:
            return []
        # A segment that starts at index b (the last breakpoint is the series' end): for pixels frame
        # b opens it, for differences x_{b+1} - x_b, the first step after a turn at frame b.
        starts = detector.predict(pen=self.penalty if penalty is None else penalty)[:-1]
        return [b - 1 for b in starts if 0 <= b - 1 < length][: self.n_keyframes]

    def __call__(self, clips: Tensor, future_length: Tensor) -> list[list[int]]:
        frames = clips.detach().cpu().numpy()
        return [self.positions(self.detector(clip, length), length) for clip, length in zip(frames, future_length.tolist())]
