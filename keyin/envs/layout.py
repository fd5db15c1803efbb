"""Random layouts of the pushing scene: wall, puck start and goal (paper App. 7, docs/pushing.md).

All lengths are world units on a table whose free area is ``[-arena_half, arena_half]²`` (the
camera sees ``[-1, 1]²``). In the wall frame (along the wall, along its normal):

* the wall's centre line is offset from the table centre by ``U[wall_offset]`` along the normal
  (random sign) and shifted by ``U[-wall_shift, wall_shift]`` along the wall, so the pusher's home
  (the table centre) is never inside it;
* the puck starts on the home side of the wall at ``U[start_distance]`` from the wall's centre line
  and ``U[-lateral, lateral]`` along it; the goal mirrors it on the far side. Starting on the
  pusher's side lets the pusher reach behind the puck without going round the wall first; the
  random normal sign still puts the start on either side of the table equally often.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from keyin.envs.geometry import from_wall_frame, wall_corners


@dataclass(frozen=True)
class Layout:
    """One episode's geometry.

    Attributes:
        wall: (5,) ``(cx, cy, half_length, half_thickness, angle)``.
        start: (2,) puck start position.
        goal: (2,) puck goal position.
        home: (2,) pusher start position.
    """

    wall: np.ndarray
    start: np.ndarray
    goal: np.ndarray
    home: np.ndarray

    def as_array(self) -> np.ndarray:
        """(11,) float64: wall (5), start (2), goal (2), home (2)."""
        return np.concatenate([self.wall, self.start, self.goal, self.home]).astype(np.float64)

    @classmethod
    def from_array(cls, values: np.ndarray) -> "Layout":
        """Inverse of :meth:`as_array`."""
        values = np.asarray(values, dtype=np.float64)
        return cls(values[:5].copy(), values[5:7].copy(), values[7:9].copy(), values[9:11].copy())


@dataclass(frozen=True)
class LayoutSampler:
    """Draws :class:`Layout` s; plain numbers only (mirrors ``conf/dataset/pushing.yaml``)."""

    arena_half: float = 0.95
    puck_radius: float = 0.06
    pusher_radius: float = 0.04
    wall_half_length: tuple[float, float] = (0.40, 0.45)
    wall_half_thickness: float = 0.03
    wall_max_angle_deg: float = 20.0
    wall_offset: tuple[float, float] = (0.12, 0.20)
    wall_shift: float = 0.10
    min_end_gap: float = 0.25
    start_distance: tuple[float, float] = (0.40, 0.48)
    lateral: float = 0.12
    max_draws: int = 100

    def sample(self, rng: np.random.Generator) -> Layout:
        """A valid layout; raises ``RuntimeError`` if ``max_draws`` draws all fail the checks."""
        for _ in range(self.max_draws):
            layout = self._draw(rng)
            if self.is_valid(layout):
                return layout
        raise RuntimeError(f"no valid pushing layout in {self.max_draws} draws; check the ranges")

    def _draw(self, rng: np.random.Generator) -> Layout:
        angle = np.deg2rad(rng.uniform(-self.wall_max_angle_deg, self.wall_max_angle_deg))
        half_length = rng.uniform(*self.wall_half_length)
        side = rng.choice([-1.0, 1.0])  # the wall lies on this side of the table centre
        offset = side * rng.uniform(*self.wall_offset)
        shift = rng.uniform(-self.wall_shift, self.wall_shift)
        axis = np.array([np.cos(angle), np.sin(angle)])
        normal = np.array([-np.sin(angle), np.cos(angle)])
        centre = offset * normal + shift * axis
        wall = np.array([centre[0], centre[1], half_length, self.wall_half_thickness, angle])
        start_local = [rng.uniform(-self.lateral, self.lateral), -side * rng.uniform(*self.start_distance)]
        goal_local = [rng.uniform(-self.lateral, self.lateral), side * rng.uniform(*self.start_distance)]
        start, goal = from_wall_frame(np.array([start_local, goal_local]), wall)
        return Layout(wall=wall, start=start, goal=goal, home=np.zeros(2))

    def is_valid(self, layout: Layout) -> bool:
        """Wall ends far enough from the border; puck start and goal on the table, clear of the home."""
        corners = wall_corners(layout.wall)
        if np.any(np.abs(corners) > self.arena_half - self.min_end_gap):
            return False
        reach = self.arena_half - self.puck_radius - 0.05
        if np.any(np.abs(layout.start) > reach) or np.any(np.abs(layout.goal) > reach):
            return False
        clearance = self.puck_radius + self.pusher_radius + 0.02
        return bool(np.linalg.norm(layout.start - layout.home) > clearance)
