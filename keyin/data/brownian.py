"""Structured Brownian motion (paper §4 "Datasets", §4.1.1): a ball moving straight, turning at random vertices.

A clip is ``n_cond + n_future`` binary 32x32 frames of one disc. The ball moves at constant speed
along straight segments of ``U{segment_min..segment_max}`` frames; at each vertex it turns by at
least ``min_turn_deg`` to a heading that keeps the whole next segment inside the canvas (no wall
bounces, so every direction change is a keyframe). A random burn-in of ``U{0..burn_max}`` frames
gives the clip a random phase. Ground-truth keyframes are the vertex frames.
Each clip depends only on ``seed + index``, so any worker count yields the same data.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

MAX_HEADING_DRAWS = 1000


@dataclass(frozen=True)
class BrownianGenerator:
    """Generator of Structured Brownian motion clips; plain numbers only so it pickles."""

    image_size: int = 32
    radius: float = 2.0
    speed: float = 2.0
    segment_min: int = 6
    segment_max: int = 8
    min_turn_deg: float = 30.0
    burn_max: int = 7
    n_cond: int = 5
    n_future: int = 30

    @property
    def clip_length(self) -> int:
        return self.n_cond + self.n_future

    def trajectory(self, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Positions and vertex flags of one clip.

        Returns:
            positions: (L, 2) float64 (x, y) in pixels, L = clip_length.
            vertices: (L,) bool, True where the direction changes.
        """
        burn = int(rng.integers(0, self.burn_max + 1))
        total = burn + self.clip_length
        low, high = self.radius, self.image_size - self.radius
        position = rng.uniform(low, high, size=2)
        positions = [position]
        vertex_frames = []
        heading = None
        while len(positions) < total:
            length = int(rng.integers(self.segment_min, self.segment_max + 1))
            heading = self._draw_heading(rng, position, heading, length, low, high)
            step = self.speed * np.array([np.cos(heading), np.sin(heading)])
            segment = position + step * np.arange(1, length + 1)[:, None]
            positions.extend(segment)
            position = segment[-1]
            vertex_frames.append(len(positions) - 1)
        positions = np.stack(positions[burn:total])
        vertices = np.zeros(total, dtype=bool)
        # A vertex is visible only with a frame on each side of it inside the clip.
        vertices[[v for v in vertex_frames if burn < v < total - 1]] = True
        return positions, vertices[burn:total]

    def _draw_heading(
        self,
        rng: np.random.Generator,
        position: np.ndarray,
        previous: float | None,
        length: int,
        low: float,
        high: float,
    ) -> float:
        """A heading that keeps the segment inside [low, high]² and turns by >= min_turn_deg."""
        reach = self.speed * length
        min_turn = np.deg2rad(self.min_turn_deg)
        for _ in range(MAX_HEADING_DRAWS):
            heading = rng.uniform(0.0, 2.0 * np.pi)
            end = position + reach * np.array([np.cos(heading), np.sin(heading)])
            if not (np.all(end >= low) and np.all(end <= high)):
                continue
            if previous is not None:
                turn = abs((heading - previous + np.pi) % (2.0 * np.pi) - np.pi)
                if turn < min_turn:
                    continue
            return heading
        raise RuntimeError(f"no admissible heading from {position} after {MAX_HEADING_DRAWS} draws")

    def render(self, positions: np.ndarray) -> np.ndarray:
        """Binary frames of a disc at each position.

        Args:
            positions: (L, 2) (x, y) in pixels.
        Returns:
            (L, H, W, 1) uint8 in {0, 255}; a pixel is lit iff its centre is within ``radius``.
        """
        centres = np.arange(self.image_size) + 0.5
        dx = centres[None, None, :] - positions[:, 0, None, None]
        dy = centres[None, :, None] - positions[:, 1, None, None]
        lit = dx**2 + dy**2 <= self.radius**2
        return (lit.astype(np.uint8) * 255)[..., None]

    def generate(self, index: int, seed: int) -> tuple[dict[str, np.ndarray], int]:
        """One clip, deterministic in ``seed + index``.

        Returns:
            arrays: ``frames`` (L, H, W, 1) uint8, ``length`` () int32, ``keyframes`` (L,) bool,
                ``positions`` (L, 2) float32.
            attempts: 1 (Brownian clips are never rejected).
        """
        rng = np.random.default_rng(seed + index)
        positions, vertices = self.trajectory(rng)
        arrays = {
            "frames": self.render(positions),
            "length": np.int32(self.clip_length),
            "keyframes": vertices,
            "positions": positions.astype(np.float32),
        }
        return arrays, 1


def direction_change_frames(positions: np.ndarray, tol: float = 1e-4) -> np.ndarray:
    """Frames where the step before differs from the step after (first and last never count).

    Args:
        positions: (L, 2).
    Returns:
        (L,) bool.
    """
    steps = np.diff(positions, axis=0)
    turns = np.linalg.norm(steps[1:] - steps[:-1], axis=-1) > tol
    return np.concatenate([[False], turns, [False]])
