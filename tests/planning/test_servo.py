"""The low-level servo: subgoal switching, reaching a nearby subgoal, image targets, config, and
the servo that sees only pixels."""


import numpy as np
import pytest
from omegaconf import OmegaConf

from keyin.envs.geometry import apply_homography
from keyin.envs.segmentation import puck_centroid
from keyin.errors import ConfigError
from keyin.planning.cem import sample_gaussian
from keyin.planning.rollout import BatchRollout
from keyin.planning.servo import (
    CONFIG_KEYS,
    ServoParams,
    advance_subgoal,
    pixel_cost,
    projected_puck,
    puck_observer,
    run_servo,
    segmented_puck,
    subgoal_pixels,
)
from tests.configs import CONFIGS

# A small, fast budget; the pusher starts right behind the puck.
FAST = ServoParams(horizon=4, samples=40, elites=5, iterations=2, max_timesteps=8)


def pixels(env, world: list[list[float]]) -> np.ndarray:
    return apply_homography(env.physics.homography(), np.array(world))


def test_advance_subgoal_on_reach_timeout_and_never_past_the_goal():
    far = np.array([9.0, 9.0, 9.0])
    assert advance_subgoal(0, 3, far, 3.0, 10) == 0
    assert advance_subgoal(0, 10, far, 3.0, 10) == 1  # timeout: one subgoal on
    assert advance_subgoal(0, 0, np.array([1.0, 2.0, 9.0]), 3.0, 10) == 2  # past every reached one
    assert advance_subgoal(1, 0, np.array([9.0, 1.0, 1.0]), 3.0, 10) == 2
    assert advance_subgoal(2, 50, np.array([0.0, 0.0, 0.0]), 3.0, 10) == 2  # the goal is the last


def test_reaches_a_nearby_subgoal_and_switches(env):
    targets = pixels(env, [[0.0, 0.0], [0.0, 0.15]])
    result = run_servo(env, targets, FAST, np.random.default_rng(0))
    switch = int(np.argmax(result.subgoal == 1))
    assert 0 < switch <= 5  # reached within a few steps, well before the 10-step timeout
    assert np.all(result.subgoal[:switch] == 0) and np.all(result.subgoal[switch:] == 1)
    reached = np.linalg.norm(pixels(env, result.puck[switch]) - targets[0])
    assert reached < FAST.subgoal_threshold_px
    assert np.linalg.norm(pixels(env, result.puck[switch - 1]) - targets[0]) >= FAST.subgoal_threshold_px
    assert result.puck.shape == (len(result.subgoal) + 1, 2) and result.actions.shape == (len(result.subgoal), 2)
    assert np.all(np.abs(result.actions) <= 1.0)


def test_stops_at_the_goal_and_measures_the_error(env):
    goal = env.task.layout.goal
    targets = pixels(env, [[0.0, -0.15]])
    params = ServoParams(horizon=4, samples=40, elites=5, iterations=2, max_timesteps=10)
    result = run_servo(env, targets, params, np.random.default_rng(1))
    assert result.reached_goal and len(result.subgoal) < params.max_timesteps
    assert result.final_error == pytest.approx(np.linalg.norm(result.puck[-1] - goal))  # nothing in between


def test_switches_on_timeout(env):
    # The first subgoal is across the table: never reached in 3 steps; the goal is then kept.
    targets = pixels(env, [[0.8, 0.8], [0.0, -0.25]])
    params = ServoParams(horizon=3, samples=20, elites=5, iterations=1, max_timesteps=5,
                         max_steps_per_subgoal=3, goal_threshold_px=0.0)
    result = run_servo(env, targets, params, np.random.default_rng(2))
    np.testing.assert_array_equal(result.subgoal, [0, 0, 0, 1, 1])
    assert not result.reached_goal


def test_subgoal_images_invisible_subgoals_and_goal_check(env):
    image = env.physics.render_top()
    np.testing.assert_allclose(subgoal_pixels(image[None])[0], env.physics.puck_pixel(), atol=0.3)
    empty = np.full_like(image, 200)
    targets = subgoal_pixels(np.stack([empty, image]))
    assert np.isnan(targets[0]).all()
    params = ServoParams(horizon=2, samples=10, elites=2, iterations=1, max_timesteps=2, goal_threshold_px=0.0)
    result = run_servo(env, targets, params, np.random.default_rng(3))
    np.testing.assert_array_equal(result.subgoal, [1, 1])  # the invisible subgoal is skipped
    with pytest.raises(ValueError, match="goal"):
        run_servo(env, targets[::-1], params, np.random.default_rng(3))


def test_params_from_the_planner_config():
    config = OmegaConf.load(CONFIGS / "planner" / "low_level" / "servo.yaml")
    assert set(config) == set(CONFIG_KEYS)  # every planner includes these
    params = ServoParams.from_config(config)
    assert params == ServoParams()  # the dataclass defaults are the paper's / the config's numbers
    assert params.cem_params().low == -1.0 and params.cem_params().samples == 200


# Joint positions (pusher x, y, puck x, y) in the conftest layout: at rest, pusher touching the puck,
# puck touching the wall's lower face, puck in the border's corner, pusher overlapping the puck.
STATES = np.array([
    [0.0, -0.42, 0.0, -0.3],
    [0.0, -0.2, 0.0, -0.1],
    [0.05, 0.4, 0.0, 0.46],
    [0.5, 0.5, 0.89, -0.89],
    [0.3, 0.3, 0.33, 0.32],
])
OUT_OF_VIEW = np.array([[0.0, 0.0, 3.0, 0.0]])


def test_the_segmented_puck_agrees_with_the_projected_one_within_a_pixel(env):
    seen = segmented_puck(env.task.scene, env.physics.wall(), STATES)
    true = projected_puck(env.physics.homography(), STATES)
    assert np.linalg.norm(seen - true, axis=-1).max() < 0.5
    assert np.isnan(segmented_puck(env.task.scene, env.physics.wall(), OUT_OF_VIEW)).all()


def mujoco_cost(env, qpos: np.ndarray, target: np.ndarray) -> float:
    """Brute force: one state rendered by MuJoCo's own camera, segmented; inf without a puck."""
    with env.physics.reset_context():
        env.physics.set_positions(qpos[2:4], qpos[0:2])
    centroid, _ = puck_centroid(env.physics.render_top())
    return float(np.linalg.norm(centroid - target)) if not np.isnan(centroid).any() else np.inf


def test_the_pixel_cost_of_a_batch_is_each_final_frame_rendered_and_segmented(env):
    plans = sample_gaussian(np.zeros((4, 2)), 1.0, 12, np.random.default_rng(4), -1.0, 1.0)
    finals = np.concatenate([BatchRollout(env, 2).final_qpos(plans), OUT_OF_VIEW])
    target = np.array([30.0, 38.0])
    costs = pixel_cost(puck_observer(env, "pixels")(finals), target)
    assert costs[-1] == np.inf and np.isfinite(costs[:-1]).all()
    np.testing.assert_array_equal(costs, [mujoco_cost(env, qpos, target) for qpos in finals])


def test_the_pixel_servo_reaches_the_goal_like_the_state_one(env):
    targets = pixels(env, [[0.0, -0.15]])
    params = ServoParams(horizon=4, samples=40, elites=5, iterations=2, max_timesteps=10, observe="pixels")
    result = run_servo(env, targets, params, np.random.default_rng(1))
    assert result.reached_goal and len(result.subgoal) < params.max_timesteps
    assert np.linalg.norm(pixels(env, result.puck[-1]) - targets[0]) < params.goal_threshold_px + 0.5


def test_an_unknown_observation_is_refused():
    with pytest.raises(ConfigError, match="servo_observe='rgb' must be one of state, pixels"):
        ServoParams(observe="rgb")
