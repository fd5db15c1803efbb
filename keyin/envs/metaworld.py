"""Meta-World's scripted experts as demonstrators: the environment set-up, the phase each expert is
in, and one episode with varied timing (docs/metaworld.md).

Meta-World (``pip install metaworld==3.0.0``; 3.1 pins a MuJoCo that dm-control refuses) ships an
expert policy per task whose target position is chosen by one if/elif/else chain (reach above the
object, descend, grasp, carry ...). :class:`PhaseTracer` reads that chain from the policy's source
and labels every step with the branch the expert took, so the phase switches are labels no method
here sees. :func:`run_episode` varies the timing the shipped tasks keep nearly fixed: a random hand
start, a per-episode speed cap on the expert's action and a random pause at each new phase.
"""

from __future__ import annotations

import ast
import inspect
import sys
import textwrap
import warnings
from dataclasses import dataclass
from types import CodeType, FrameType
from typing import Any, Callable

import numpy as np

WELD_ROW = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, 5.0, 0.0)  # anchor, relpose, torque scale, 0
INSTALL_HINT = "pip install 'metaworld==3.0.0' packaging (or pip install 'keyin[sim]')"


def import_metaworld() -> Any:
    """The ``metaworld`` module with its mocap welds fixed for MuJoCo >= 3.17 (idempotent).

    metaworld 3.0 writes an 11-number row into each weld of ``model.eq_data``; MuJoCo 3.17 stores 12
    and refuses the row at env construction. The replacement writes metaworld's row, widened by the
    number MuJoCo compiles for a weld whose relative pose is given (0).

    Raises:
        ImportError: metaworld is not installed (the message says how to install it).
        RuntimeError: metaworld's layout is not the one this fix was written for.
    """
    try:
        import metaworld
        import mujoco
        from metaworld.sawyer_xyz_env import SawyerMocapBase
    except ImportError as err:
        raise ImportError(f"dataset=metaworld needs Meta-World: {INSTALL_HINT} ({err})") from None
    if getattr(SawyerMocapBase.reset_mocap_welds, "keyin_fixed", False):
        return metaworld
    if not hasattr(SawyerMocapBase, "reset_mocap_welds"):
        raise RuntimeError("metaworld.sawyer_xyz_env.SawyerMocapBase has no reset_mocap_welds; keyin supports metaworld 3.0.0")

    def reset_mocap_welds(env: Any) -> None:
        data = env.model.eq_data
        if env.model.nmocap == 0 or data is None:
            return
        width = data.shape[1]
        if width not in (11, 12):
            raise RuntimeError(f"MuJoCo stores {width} numbers per equality constraint; keyin's weld fix knows 11 and 12")
        for row, kind in enumerate(env.model.eq_type):
            if kind == mujoco.mjtEq.mjEQ_WELD:
                data[row] = WELD_ROW[:width]

    reset_mocap_welds.keyin_fixed = True  # type: ignore[attr-defined]
    SawyerMocapBase.reset_mocap_welds = reset_mocap_welds
    return metaworld


def check_tasks(tasks: tuple[str, ...]) -> None:
    """Refuse task names Meta-World does not have or whose expert keyin cannot read phases from.

    Raises:
        ValueError: naming the unknown tasks and the known ones.
    """
    from metaworld.policies import ENV_POLICY_MAP

    known = sorted(set(import_metaworld().ALL_V3_ENVIRONMENTS) & set(ENV_POLICY_MAP))
    unknown = [task for task in tasks if task not in known]
    if unknown:
        raise ValueError(f"unknown Meta-World task(s) {unknown}; the tasks with an expert are {known}")


def make_env(task: str, max_steps: int) -> Any:
    """Meta-World's ``task`` (e.g. ``"pick-place-v3"``) with the goal observed (the experts need it),
    a fresh object and goal placement drawn at every ``reset()`` from ``env.np_random``, and an
    episode limit of ``max_steps``."""
    metaworld = import_metaworld()
    envs = metaworld.ALL_V3_ENVIRONMENTS
    if task not in envs:
        raise ValueError(f"unknown Meta-World task {task!r}; the tasks are {sorted(envs)}")
    env = envs[task]()
    env._partially_observable = False
    env.__dict__.pop("sawyer_observation_space", None)  # cached with the goal hidden: step() would clip it to 0
    env._set_task_called = True
    env._freeze_rand_vec = False
    env.seeded_rand_vec = True
    env.max_path_length = max_steps
    return env


def expert(task: str) -> Any:
    """The scripted expert policy of ``task``."""
    from metaworld.policies import ENV_POLICY_MAP

    return ENV_POLICY_MAP[task]()


def branch_lines(function: Callable) -> dict[int, int]:
    """Line number of each branch's first statement -> branch number (0 = the ``if``, then each
    ``elif``, then ``else``) of the first top-level if/elif/else chain in ``function``.

    Raises:
        ValueError: ``function`` has no top-level if statement.
    """
    source = textwrap.dedent(inspect.getsource(function))
    first_line = inspect.getsourcelines(function)[1]
    body = ast.parse(source).body[0].body  # type: ignore[attr-defined]
    chain = next((node for node in body if isinstance(node, ast.If)), None)
    if chain is None:
        raise ValueError(f"{function.__qualname__} has no top-level if/elif/else chain to read phases from")
    lines: dict[int, int] = {}
    node: Any = chain
    while True:
        lines[node.body[0].lineno + first_line - 1] = len(lines)
        if len(node.orelse) == 1 and isinstance(node.orelse[0], ast.If):
            node = node.orelse[0]
            continue
        if node.orelse:
            lines[node.orelse[0].lineno + first_line - 1] = len(lines)
        return lines


class PhaseTracer:
    """The expert's action and the branch its target took: ``tracer(obs) -> (action, phase)``.

    The branching function is the policy's ``_desired_pos`` where it has one, else ``get_action``.
    Each call runs ``get_action`` under a trace hook limited to that function's code.
    """

    def __init__(self, policy: Any):
        self.policy = policy
        function = getattr(type(policy), "_desired_pos", None) or type(policy).get_action
        function = inspect.unwrap(function)
        self.code: CodeType = function.__code__
        self.lines = branch_lines(function)
        self.phase = -1

    def _trace(self, frame: FrameType, event: str, arg: Any) -> Any:
        if frame.f_code is not self.code:
            return None
        if event == "line" and self.phase < 0:
            self.phase = self.lines.get(frame.f_lineno, -1)
        return self._trace

    def __call__(self, obs: np.ndarray) -> tuple[np.ndarray, int]:
        self.phase = -1
        previous = sys.gettrace()
        sys.settrace(self._trace)
        try:
            with warnings.catch_warnings():  # every expert's gain trips "Constant(s) may be too high"; the env clips
                warnings.simplefilter("ignore", UserWarning)
                action = self.policy.get_action(obs.copy())  # some experts edit the observation in place
        finally:
            sys.settrace(previous)
        if self.phase < 0:
            raise RuntimeError(f"{type(self.policy).__name__}: no branch of its phase chain ran")
        return np.asarray(action, dtype=np.float64), self.phase


@dataclass(frozen=True)
class Timing:
    """How an episode's timing varies: the hand's start drawn in a box (``None``: the task's own),
    the expert's xyz action capped at ``s ~ U(speed_min, 1)`` per episode, and at each phase the
    expert enters for the first time a pause of ``U{0..max_pause}`` steps (arm still, grip kept)."""

    hand_low: tuple[float, float, float] | None = (-0.2, 0.45, 0.1)
    hand_high: tuple[float, float, float] | None = (0.2, 0.75, 0.3)
    speed_min: float = 0.4
    max_pause: int = 8


@dataclass
class Episode:
    """One expert episode. ``states`` has one row per observation (steps + 1)."""

    captures: list[Any]        # ``capture(env)`` of every ``capture_every``-th observation (e.g. a copy of env.data)
    phases: np.ndarray         # (steps,) int: the expert's branch at each step (a pause repeats it)
    hand: np.ndarray           # (steps + 1, 3) hand position
    actions: np.ndarray        # (steps, 4) the actions played
    success_step: int | None   # the first observation index with info["success"], None if never


def run_episode(
    env: Any,
    tracer: PhaseTracer,
    timing: Timing,
    rng: np.random.Generator,
    max_steps: int,
    stop_after_success: int,
    capture: Callable[[Any], Any],
    capture_every: int,
) -> Episode:
    """Play the expert from a reset drawn by ``rng`` until ``stop_after_success`` steps after its first
    success (or ``max_steps``), capturing every ``capture_every``-th observation (the caller renders
    the captures it keeps: a copy of ``env.data`` costs ~0.6 ms, a render ~10 ms)."""
    env.np_random = np.random.default_rng(rng.integers(2**63))
    if timing.hand_low is not None:
        env.hand_init_pos = rng.uniform(timing.hand_low, timing.hand_high)
    obs, _ = env.reset()
    speed = rng.uniform(timing.speed_min, 1.0)
    captures, phases, hand, actions = [capture(env)], [], [obs[:3].copy()], []
    seen: set[int] = set()
    pause, success_step, step = 0, None, 0
    while step < max_steps and (success_step is None or step < success_step + stop_after_success):
        action, phase = tracer(obs)
        if pause == 0 and phase not in seen:
            pause = int(rng.integers(timing.max_pause + 1)) if seen else 0
            seen.add(phase)
        if pause > 0:
            action, phase, pause = np.array([0.0, 0.0, 0.0, action[3]]), phases[-1], pause - 1
        action[:3] = np.clip(action[:3], -speed, speed)
        obs, _, _, _, info = env.step(action.astype(np.float32))
        step += 1
        phases.append(phase)
        hand.append(obs[:3].copy())
        actions.append(action)
        if success_step is None and info.get("success", 0.0) > 0:
            success_step = step
        if step % capture_every == 0:
            captures.append(capture(env))
    return Episode(captures, np.array(phases), np.array(hand), np.array(actions), success_step)


def debounced_switches(phases: np.ndarray, hold: int) -> list[int]:
    """The steps at which the expert's phase changes for good: a new phase counts once it is held
    ``hold`` steps (shorter flickers at a threshold are merged into the phase before).

    Args:
        phases: (steps,) the branch at each step; step ``t`` acts on observation ``t``.
    Returns:
        the observation indices at which each kept phase starts, the first phase excluded.
    """
    runs: list[list[int]] = []  # [phase, start, length]
    for t, phase in enumerate(phases.tolist()):
        if runs and runs[-1][0] == phase:
            runs[-1][2] += 1
        else:
            runs.append([phase, t, 1])
    kept: list[list[int]] = []
    for phase, start, length in runs:
        if kept and (length < hold or kept[-1][0] == phase):
            kept[-1][2] += length
        else:
            kept.append([phase, start, length])
    return [start for _, start, _ in kept[1:]]
