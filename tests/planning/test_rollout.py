"""Batched mujoco.rollout == the per-copy Python loop == the real environment (bit for bit)."""

import numpy as np

from keyin.planning.rollout import BatchRollout, LoopRollout, action_controls
from keyin.planning.servo import execute


def actions(n: int, seed: int = 0) -> np.ndarray:
    """(n, 4, 2) random actions, partly outside [-1, 1], biased upwards so some push the puck."""
    return np.random.default_rng(seed).normal([0.0, 0.8], 1.0, (n, 4, 2))


def test_action_controls_clip_and_hold():
    controls = action_controls(np.array([[[2.0, -0.5], [0.25, -3.0]]]), 3)
    np.testing.assert_array_equal(controls[0], [[1.0, -0.5]] * 3 + [[0.25, -1.0]] * 3)


def test_batched_equals_loop_mid_episode(env):
    for action in ([0.0, 1.0], [0.3, 0.8], [0.0, 1.0]):  # the puck is moving and in contact
        env.step(action)
    assert np.linalg.norm(env.physics.puck_velocity()) > 0.1
    plans = actions(12)
    batched = BatchRollout(env, action_repeat=2).final_qpos(plans)
    looped = LoopRollout(env, action_repeat=2).final_qpos(plans)
    np.testing.assert_array_equal(batched, looped)
    assert np.ptp(batched[:, 2:4], axis=0).max() > 0.05  # the plans moved the puck differently


def test_batched_equals_the_environment(env):
    env.step([0.0, 1.0])
    plan = actions(1, seed=3)
    predicted = BatchRollout(env, action_repeat=2).final_qpos(plan)[0]
    for action in plan[0]:
        assert not execute(env, action, 2)
    np.testing.assert_array_equal(predicted, env.physics.data.qpos)
