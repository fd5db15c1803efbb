"""Rule-based pushing demonstrator (paper App. 7; docs/pushing.md).

1. Choose a detour side (either end of the wall, uniformly) and draw ``n_pushes`` subgoals along
   the polyline start -> two detour corners -> goal, where the corners sit ``detour_margin`` outside
   the wall inflated by the puck radius. Subgoals sit at jittered arc-length shares (the first
   share is smaller: the first push also walks the pusher from its home to the puck), each off the
   line by up to ``lateral_jitter``; the last one is the goal. Subgoal sets whose straight pushes
   would pass within ``wall_clearance`` of the inflated wall are redrawn.
2. Push to each subgoal in turn: walk the pusher to a point behind the puck on the line through the
   subgoal (orbiting the puck, on the side away from the wall, when it is in the way), then push
   along that line, steering back onto it, slowing down so the puck stops at the subgoal. The
   raw frame at which the puck comes within ``reach_tolerance`` of the subgoal completes the push.
   Each push has its own speed, log-uniform in ``push_speed`` · [1 / f, f] with f =
   ``push_speed_spread`` (f = 1: every push at ``push_speed``).
3. After each push but the last the demonstrator may pause for U{0..``max_pause_frames``} saved
   frames: the pusher backs away from the puck at ``pause_speed`` (0: it waits) and the puck stays
   where the push left it. The next push starts after the pause.
4. The video keeps every ``frame_skip``-th raw frame; a push completed at raw frame ``c`` ends at
   saved frame ``ceil(c / frame_skip)``. A demo is kept only if every push spans
   ``min_push_frames``..``max_push_frames`` saved frames counted from the end of the pause before
   it (which also bounds its length).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from dm_control.rl import control

from keyin.envs.geometry import from_wall_frame, segment_crosses_box, to_wall_frame
from keyin.envs.layout import Layout


@dataclass(frozen=True)
class DemoParams:
    """Demonstrator constants (plain numbers; mirrored in ``conf/dataset/pushing.yaml``, the
    timing options ``push_speed_spread``, ``max_pause_frames``, ``pause_speed`` in ``pushing_irregular.yaml``)."""

    n_pushes: int = 6
    detour_margin: float = 0.10
    first_share: float = 0.55  # the first push's arc-length share relative to the others
    share_jitter: float = 0.2  # each share is scaled by U[1 - j, 1 + j]
    lateral_jitter: float = 0.03
    wall_clearance: float = 0.02
    push_speed: float = 0.42  # units / s while pushing (the median of each push's own speed)
    push_speed_spread: float = 1.0  # each push's speed is push_speed * f^U[-1, 1]
    max_pause_frames: int = 0  # after each push but the last, a pause of U{0..k} saved frames
    pause_speed: float = 0.0  # units / s the pusher backs away from the puck while paused (0: waits)
    move_speed: float = 1.0  # units / s while walking to the puck
    contact_gap: float = 0.02  # the pre-push point is this far behind contact
    reach_tolerance: float = 0.02
    frame_skip: int = 2
    min_push_frames: int = 4
    max_push_frames: int = 6
    max_subgoal_draws: int = 50


@dataclass
class Demo:
    """One demonstration at the raw control rate (T raw steps, T + 1 raw frames).

    Attributes:
        states: (T + 1, S) physics states (``physics.get_state()``) for rendering the frames.
        puck, pusher: (T + 1, 2) positions.
        actions: (T, 2) actions in [-1, 1]; action t moves frame t to frame t + 1.
        completions: (P,) raw frame at which each push completed.
        pauses: (P,) saved frames the demonstrator paused after each push (the last: 0).
        subgoals: (n_pushes, 2); the last is the goal.
        side: +1 / -1, the wall end the puck goes round (in the wall's own frame).
        layout: the episode's layout.
    """

    states: np.ndarray
    puck: np.ndarray
    pusher: np.ndarray
    actions: np.ndarray
    completions: np.ndarray
    pauses: np.ndarray
    subgoals: np.ndarray
    side: int
    layout: Layout

    def saved_completions(self, frame_skip: int) -> np.ndarray:
        """(P,) saved-frame index of each push completion: ceil(raw / frame_skip)."""
        return -(-self.completions // frame_skip)

    def push_lengths(self, frame_skip: int) -> np.ndarray:
        """(P,) saved frames per push, from the end of the pause before it (the first from saved
        frame 0) to its completion."""
        gaps = np.diff(self.saved_completions(frame_skip), prepend=0)
        return gaps - np.concatenate([[0], self.pauses[:-1]])


def detour_polyline(layout: Layout, side: int, puck_radius: float, margin: float) -> np.ndarray:
    """(4, 2) world points start -> corner -> corner -> goal round the ``side`` end of the wall."""
    wall = layout.wall
    start_local, goal_local = to_wall_frame(np.stack([layout.start, layout.goal]), wall)
    along = side * (wall[2] + puck_radius + margin)
    across = wall[3] + puck_radius + margin
    corners = np.array([[along, np.sign(start_local[1]) * across], [along, np.sign(goal_local[1]) * across]])
    return np.concatenate([layout.start[None], from_wall_frame(corners, wall), layout.goal[None]])


def draw_subgoals(
    layout: Layout, side: int, rng: np.random.Generator, params: DemoParams, puck_radius: float, arena: float
) -> np.ndarray | None:
    """(n_pushes, 2) subgoals along the detour, or None if no admissible draw was found."""
    polyline = detour_polyline(layout, side, puck_radius, params.detour_margin)
    lengths = np.linalg.norm(np.diff(polyline, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(lengths)])
    weights = np.ones(params.n_pushes)
    weights[0] = params.first_share
    inflate = puck_radius + params.wall_clearance
    for _ in range(params.max_subgoal_draws):
        shares = weights * rng.uniform(1 - params.share_jitter, 1 + params.share_jitter, params.n_pushes)
        targets = np.cumsum(shares)[:-1] / shares.sum() * arc[-1]
        segment = np.clip(np.searchsorted(arc, targets, side="right") - 1, 0, len(lengths) - 1)
        direction = np.diff(polyline, axis=0)[segment] / lengths[segment, None]
        points = polyline[segment] + direction * (targets - arc[segment])[:, None]
        normal = np.stack([-direction[:, 1], direction[:, 0]], axis=1)
        jitter = rng.uniform(-params.lateral_jitter, params.lateral_jitter, (len(points), 1))
        points = points + normal * jitter
        subgoals = np.concatenate([points, layout.goal[None]])
        route = np.concatenate([layout.start[None], subgoals])
        if np.any(np.abs(subgoals) > arena - puck_radius - 0.02):
            continue
        if any(segment_crosses_box(a, b, layout.wall, inflate) for a, b in zip(route[:-1], route[1:])):
            continue
        return subgoals
    return None


def draw_timing(rng: np.random.Generator, params: DemoParams) -> tuple[np.ndarray, np.ndarray]:
    """Each push's speed (n_pushes,) in units / s and the pause after it (n_pushes,) in saved
    frames; the last push has no pause."""
    speeds = params.push_speed * params.push_speed_spread ** rng.uniform(-1.0, 1.0, params.n_pushes)
    pauses = np.append(rng.integers(0, params.max_pause_frames + 1, params.n_pushes - 1), 0)
    return speeds, pauses


class PushController:
    """Walk behind the puck, then push it along the line to the subgoal (one raw step at a time)."""

    def __init__(self, params: DemoParams, puck_radius: float, pusher_radius: float, dt: float,
                 v_max: float, wall: np.ndarray, coast: float) -> None:
        self.p, self.dt, self.v_max, self.wall, self.coast = params, dt, v_max, wall, coast
        self.pusher_radius = pusher_radius
        self.contact = puck_radius + pusher_radius
        self.orbit = self.contact + params.contact_gap + 0.02

    def act(self, puck: np.ndarray, pusher: np.ndarray, subgoal: np.ndarray, push_speed: float) -> np.ndarray:
        """(2,) action in [-1, 1] for the next raw step, pushing at most at ``push_speed``."""
        offset = subgoal - puck
        distance = float(np.linalg.norm(offset))
        direction = offset / max(distance, 1e-9)
        rel = pusher - puck
        behind = -float(rel @ direction)
        lateral = abs(float(rel[0] * direction[1] - rel[1] * direction[0]))
        if behind > 0.5 * self.contact and lateral < 0.02 and behind < self.orbit + 0.02:
            # Push: command the speed that lets the puck coast to a stop at the subgoal.
            speed = min(push_speed, distance / (self.dt + self.coast))
            velocity = speed * direction + 0.5 * (puck - direction * self.contact - pusher) / self.dt
        else:
            velocity = self._walk(puck, pusher, direction)
        return self._to_action(velocity)

    def back_off(self, puck: np.ndarray, pusher: np.ndarray) -> np.ndarray:
        """(2,) action of a pause: straight away from the puck at ``pause_speed``, so it never
        touches it."""
        away = pusher - puck
        return self._to_action(self.p.pause_speed * away / max(float(np.linalg.norm(away)), 1e-9))

    def _walk(self, puck: np.ndarray, pusher: np.ndarray, direction: np.ndarray) -> np.ndarray:
        target = puck - direction * (self.contact + self.p.contact_gap)
        rel = pusher - puck
        angle_now = math.atan2(rel[1], rel[0])
        angle_goal = math.atan2(-direction[1], -direction[0])
        turn = (angle_goal - angle_now + math.pi) % (2 * math.pi) - math.pi
        if abs(turn) > math.radians(45) or float(np.linalg.norm(rel)) < self.contact + 0.005:
            # The puck is in the way: orbit it, the short way unless that runs into the wall.
            for sign in (math.copysign(1.0, turn), -math.copysign(1.0, turn)):
                angle = angle_now + sign * min(abs(turn), math.radians(60))
                waypoint = puck + self.orbit * np.array([math.cos(angle), math.sin(angle)])
                if not segment_crosses_box(pusher, waypoint, self.wall, self.pusher_radius):
                    target = waypoint
                    break
        return 0.9 * (target - pusher) / self.dt

    def _to_action(self, velocity: np.ndarray) -> np.ndarray:
        speed = float(np.linalg.norm(velocity))
        limit = self.p.move_speed
        if speed > limit:
            velocity = velocity * (limit / speed)
        return np.clip(velocity / self.v_max, -1.0, 1.0)


def run_demo(
    env: control.Environment, layout: Layout, rng: np.random.Generator, params: DemoParams
) -> Demo | None:
    """Run the demonstrator on ``layout`` in a pixel-free environment; None if the demo is rejected.

    Rejected: no admissible subgoals, a push longer than ``max_push_frames`` saved frames (the run
    stops there), one shorter than ``min_push_frames``, or a final puck farther than the scene's
    ``goal_tolerance`` from the goal. The timing (:func:`draw_timing`) is drawn after the subgoals.
    """
    scene = env.task.scene
    side = int(rng.choice([-1, 1]))
    subgoals = draw_subgoals(layout, side, rng, params, scene.puck_radius, scene.arena_half)
    if subgoals is None:
        return None
    speeds, pauses = draw_timing(rng, params)
    env.task.pin_layout(layout)
    env.reset()
    physics = env.physics
    controller = PushController(params, scene.puck_radius, scene.pusher_radius, scene.control_timestep,
                                scene.v_max, layout.wall, coast=scene.puck_mass / scene.puck_damping)
    states, pucks, pushers = [physics.get_state()], [physics.puck_position()], [physics.pusher_position()]
    actions, completions = [], []

    def record(action: np.ndarray) -> None:
        env.step(action)
        actions.append(action)
        states.append(physics.get_state())
        pucks.append(physics.puck_position())
        pushers.append(physics.pusher_position())

    skip, budget = params.frame_skip, params.max_push_frames * params.frame_skip
    push_start = 0  # the saved frame the current push started from: the previous one's end or pause
    while len(completions) < len(subgoals):
        push = len(completions)
        record(controller.act(pucks[-1], pushers[-1], subgoals[push], speeds[push]))
        frame = len(actions)
        if np.linalg.norm(pucks[-1] - subgoals[push]) < params.reach_tolerance:
            completions.append(frame)
            saved = -(-frame // skip)
            if not params.min_push_frames <= saved - push_start <= params.max_push_frames:
                return None
            push_start = saved + pauses[push]
            # A pause fills the rest of the completion's saved frame and p more; without one the
            # next push starts at once, mid-frame.
            while pauses[push] and len(actions) < push_start * skip:
                record(controller.back_off(pucks[-1], pushers[-1]))
        elif frame - push_start * skip > budget:
            return None
    while len(actions) % skip:  # finish the last saved frame with the pusher at rest
        record(np.zeros(2))
    if np.linalg.norm(pucks[-1] - layout.goal) > scene.goal_tolerance:
        return None
    return Demo(
        states=np.stack(states), puck=np.stack(pucks), pusher=np.stack(pushers),
        actions=np.stack(actions), completions=np.asarray(completions), pauses=pauses, subgoals=subgoals,
        side=side, layout=layout,
    )
