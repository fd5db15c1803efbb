"""The Gymnasium registration: gymnasium.make("keyin/Pushing-v0")."""

import gymnasium
import numpy as np
import pytest

import keyin.envs  # noqa: F401  (registers keyin/Pushing-v0)


@pytest.fixture(scope="module")
def env():
    env = gymnasium.make("keyin/Pushing-v0", render_mode="rgb_array")
    yield env
    env.close()


def test_make_reset_step(env):
    observation, info = env.reset(seed=0)
    assert observation["pixels"].shape == (64, 64, 3) and observation["pixels"].dtype == np.uint8
    assert env.observation_space.contains(observation)
    assert info["goal_distance"] > 0.5
    observation, reward, terminated, truncated, info = env.step(env.action_space.sample())
    assert env.observation_space.contains(observation)
    assert 0.0 <= reward <= 1.0 and not terminated and not truncated
    assert env.render().shape == (64, 64, 3)


def test_reset_seed_is_reproducible(env):
    first, _ = env.reset(seed=42)
    second, _ = env.reset(seed=42)
    third, _ = env.reset(seed=43)
    assert np.array_equal(first["pixels"], second["pixels"]) and np.array_equal(first["wall"], second["wall"])
    assert not np.array_equal(first["wall"], third["wall"])


def test_out_of_range_action_is_clipped(env):
    env.reset(seed=1)
    big, *_ = env.step(np.array([10.0, -10.0], dtype=np.float32))
    env.reset(seed=1)
    unit, *_ = env.step(np.array([1.0, -1.0], dtype=np.float32))
    assert np.array_equal(big["pusher"], unit["pusher"])
    with pytest.raises(ValueError, match=r"pushing actions are 2 finite numbers in \[-1, 1\], got"):
        env.step(np.array([np.inf, 0.0]))


def test_pinned_layout_option(env):
    layout = np.array([0.0, 0.2, 0.4, 0.03, 0.1, 0.1, -0.3, -0.1, 0.6, 0.0, 0.0])
    observation, _ = env.reset(options={"layout": layout})
    assert np.allclose(observation["wall"], layout[:5]) and np.allclose(observation["puck"], layout[5:7])
