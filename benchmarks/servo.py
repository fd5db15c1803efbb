"""Low-level servo speed: batched ``mujoco.rollout`` against the per-copy Python loop, same results.

    OMP_NUM_THREADS=1 python benchmarks/servo.py --steps 6 --loop-steps 2 --threads 1 2 \
        --out benchmarks/results/servo.md

On planning task ``--task`` (the planning split of seed 0, as ``write_planning_tasks`` draws it;
subgoals = the demo's puck at each push completion, the goal = the goal image's puck centroid):

1. the costs of one batch of ``samples`` random plans (pixel distance of the final puck to the first
   subgoal) from :class:`BatchRollout` and :class:`LoopRollout`, at the task's start and at the end
   of the last run, must be identical (max |difference| printed);
2. the servo from the task's start (seed 0) with the per-copy loop for ``--loop-steps`` executed
   steps, then with :class:`MjStepLoop` and with :class:`BatchRollout` (each ``--threads`` count)
   for ``--steps``: executed steps / s, and whether each trajectory starts with exactly the loop's;
3. one CEM iteration's rollouts alone (``samples`` plans): microseconds per physics step, best of
   ``REPEATS`` (the machine may be shared).

A third simulator, :class:`MjStepLoop` (benchmark only), loops over the plans in Python on one raw
``MjData`` (``mj_setState``, then ``mj_step`` per environment step): the same C physics as the batched
rollout without dm_control's ``Physics.copy``, so it separates the two sources of the speed-up.
"""

from __future__ import annotations

import argparse
import datetime
import os
import platform
import sys
import time
from pathlib import Path

import mujoco
import numpy as np
from common import cpu_model, publish

import keyin.envs
from keyin.data.generate import split_seed
from keyin.data.pushing import PushingGenerator
from keyin.envs.geometry import apply_homography
from keyin.envs.layout import Layout
from keyin.planning.cem import sample_gaussian
from keyin.planning.rollout import BatchRollout, LoopRollout, Simulator, env_substeps
from keyin.planning.servo import ServoParams, ServoTrajectory, pixel_cost, projected_puck, run_servo, subgoal_pixels

REPEATS = 3


class MjStepLoop:
    """Per-plan Python loop on one raw ``MjData``: restore the state, ``mj_step`` each env step."""

    def __init__(self, env, action_repeat: int) -> None:
        self._batch = BatchRollout(env, action_repeat)  # only for its initial_state()
        self._model = env.physics.model.ptr
        self._data = mujoco.MjData(self._model)
        self._repeat, self._substeps = action_repeat, env_substeps(env)

    def final_qpos(self, actions: np.ndarray) -> np.ndarray:
        state, warmstart = self._batch.initial_state()
        finals = []
        for sequence in np.clip(actions, -1.0, 1.0):
            mujoco.mj_setState(self._model, self._data, state[0], mujoco.mjtState.mjSTATE_FULLPHYSICS)
            self._data.qacc_warmstart[:] = warmstart[0]
            for action in sequence:
                self._data.ctrl[:] = action
                mujoco.mj_step(self._model, self._data, self._repeat * self._substeps)
            finals.append(self._data.qpos.copy())
        return np.stack(finals)


def task_env(task: int) -> tuple[object, np.ndarray]:
    """A pixel-free environment at planning task ``task`` and its (K, 2) subgoal pixels."""
    generator = PushingGenerator()
    seed = split_seed(0, "planning")
    planning = generator.planning_task(task, seed)
    demo, _ = generator.demo(task, seed)
    env = keyin.envs.load("pushing", seed=0, pixels=False)
    env.task.pin_layout(Layout.from_array(planning["layout"]), planning["state"])
    env.reset()
    intermediate = apply_homography(env.physics.homography(), demo.puck[demo.completions[:-1]])
    return env, np.concatenate([intermediate, subgoal_pixels(planning["goal_image"][None])])


def timed_servo(env, targets, steps: int, simulator: Simulator) -> tuple[ServoTrajectory, float]:
    """``steps`` servo steps from the task's start (seed 0); the trajectory and executed steps / s."""
    env.reset()
    start = time.perf_counter()
    result = run_servo(env, targets, ServoParams(max_timesteps=steps, goal_threshold_px=0.0),
                       np.random.default_rng(0), simulator)
    return result, len(result.subgoal) / (time.perf_counter() - start)


def same_prefix(short: ServoTrajectory, long: ServoTrajectory) -> bool:
    """Whether ``long`` starts with exactly the steps of ``short``."""
    n = len(short.subgoal)
    return (np.array_equal(short.actions, long.actions[:n]) and np.array_equal(short.puck, long.puck[: n + 1])
            and np.array_equal(short.plan_cost, long.plan_cost[:n]))


def random_plans(params: ServoParams, seed: int) -> np.ndarray:
    """(samples, horizon, 2) plans as the first CEM iteration draws them."""
    shape = (params.horizon, 2)
    return sample_gaussian(np.zeros(shape), params.init_std, params.samples, np.random.default_rng(seed),
                           -params.max_action, params.max_action)


def cost_difference(env, target: np.ndarray, params: ServoParams, seed: int) -> float:
    """Max |cost difference| (pixels) between the two simulators on one batch of plans from now."""
    plans = random_plans(params, seed)
    homography = env.physics.homography()
    costs = [pixel_cost(projected_puck(homography, simulator.final_qpos(plans)), target)
             for simulator in (BatchRollout(env, params.action_repeat), LoopRollout(env, params.action_repeat))]
    return float(np.abs(costs[0] - costs[1]).max())


def physics_step_us(env, simulator: Simulator, params: ServoParams) -> float:
    """Microseconds per physics step of one CEM iteration's rollouts (best of ``REPEATS``)."""
    plans = random_plans(params, seed=1)
    best = np.inf
    for _ in range(REPEATS):
        start = time.perf_counter()
        simulator.final_qpos(plans)
        best = min(best, time.perf_counter() - start)
    return best / (params.samples * params.horizon * params.action_repeat * env_substeps(env)) * 1e6


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", type=int, default=0)
    parser.add_argument("--steps", type=int, default=6, help="executed servo steps, fast simulators")
    parser.add_argument("--loop-steps", type=int, default=2, help="executed servo steps, per-copy loop")
    parser.add_argument("--threads", type=int, nargs="+", default=[1])
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args()
    load_before = os.getloadavg()
    env, targets = task_env(args.task)
    params = ServoParams()
    env.reset()
    start_difference = cost_difference(env, targets[0], params, seed=2)

    reference, reference_rate = timed_servo(env, targets, args.loop_steps, LoopRollout(env, params.action_repeat))
    rows = [("per-copy Python loop (`LoopRollout`)", args.loop_steps, reference_rate,
             physics_step_us(env, LoopRollout(env, params.action_repeat), params), "reference")]
    fast = [("raw `mj_step` Python loop, one `MjData` (`MjStepLoop`)", MjStepLoop(env, params.action_repeat))]
    fast += [(f"`mujoco.rollout`, {n} thread{'s' * (n > 1)} (`BatchRollout`)",
              BatchRollout(env, params.action_repeat, n)) for n in args.threads]
    for name, simulator in fast:
        trajectory, rate = timed_servo(env, targets, args.steps, simulator)
        same = "identical" if same_prefix(reference, trajectory) else "DIFFERENT"
        rows.append((name, args.steps, rate, physics_step_us(env, simulator, params), same))
    end_difference = cost_difference(env, targets[0], params, seed=3)
    load_after = os.getloadavg()

    per_step = params.samples * params.iterations * params.horizon * params.action_repeat * env_substeps(env)
    command = "python " + " ".join([Path(sys.argv[0]).as_posix(), *sys.argv[1:]])
    report = "\n".join([
        "# Low-level servo: batched rollouts vs the per-copy Python loop",
        "",
        f"- command: `OMP_NUM_THREADS={os.environ.get('OMP_NUM_THREADS', 'unset')} {command}`",
        f"- machine: {cpu_model()}, {os.cpu_count()} cores, {platform.platform()}; mujoco {mujoco.__version__}",
        f"- date: {datetime.datetime.now().isoformat(timespec='minutes')}",
        f"- load average (1 min) before / after: {load_before[0]:.2f} / {load_after[0]:.2f}",
        f"- servo: {params.samples} samples x {params.iterations} iterations x {params.horizon} actions x "
        f"{params.action_repeat} env steps x {env_substeps(env)} physics steps = {per_step:,} physics steps per "
        f"executed step; planning task {args.task}, {len(targets)} subgoals",
        "",
        "| simulator | executed steps | executed steps / s | speed-up | us / physics step | trajectory vs loop |",
        "|---|---|---|---|---|---|",
        *[f"| {name} | {steps} | {rate:.3f} | {rate / reference_rate:.1f}x | {us:.2f} | {same} |"
          for name, steps, rate, us, same in rows],
        "",
        f"Costs of the same {params.samples} plans, batched vs loop, max |difference| in pixels: "
        f"{start_difference:.3g} at the task's start, {end_difference:.3g} after the last run.",
        "",
    ])
    publish(report, args.out)


if __name__ == "__main__":
    main()
