"""The rule-based demonstrator: success rate, push lengths, subgoals clear of the wall, and the
timing options (regular by default; dataset=pushing_irregular's pushes of 3-9 frames and pauses)."""

import numpy as np
import pytest
from hydra import compose, initialize_config_module
from hydra.utils import instantiate

import keyin.envs
from keyin.cli.app import CONFIG_MODULE
from keyin.envs.demonstrator import DemoParams, detour_polyline, draw_subgoals, draw_timing, run_demo
from keyin.envs.geometry import segment_crosses_box, shortest_path_length


@pytest.fixture(scope="module")
def env():
    return keyin.envs.load("pushing", seed=0, pixels=False)


def test_subgoals_clear_the_wall_and_end_at_the_goal(env):
    sampler = env.task.sampler
    params = DemoParams()
    for seed in range(20):
        rng = np.random.default_rng(seed)
        layout = sampler.sample(rng)
        side = 1 if seed % 2 else -1
        subgoals = draw_subgoals(layout, side, rng, params, 0.06, 0.95)
        assert subgoals is not None and subgoals.shape == (6, 2)
        assert np.array_equal(subgoals[-1], layout.goal)
        route = np.concatenate([layout.start[None], subgoals])
        assert not any(segment_crosses_box(a, b, layout.wall, 0.06) for a, b in zip(route[:-1], route[1:]))
        # The detour polyline goes round the chosen end: longer than (or equal to) the geodesic.
        polyline = detour_polyline(layout, side, 0.06, params.detour_margin)
        length = np.sum(np.linalg.norm(np.diff(polyline, axis=0), axis=1))
        assert length >= shortest_path_length(layout.start, layout.goal, layout.wall, 0.06) - 1e-9


def test_success_rate_and_push_lengths(env):
    params = DemoParams()
    sampler = env.task.sampler
    demos = [run_demo(env, sampler.sample(rng), rng, params) for rng in map(np.random.default_rng, range(16))]
    accepted = [demo for demo in demos if demo is not None]
    assert len(accepted) >= 6  # measured ~65 % acceptance (docs/pushing.md)
    for demo in accepted:
        lengths = demo.push_lengths(params.frame_skip)
        assert len(lengths) == 6 and np.all((lengths >= 4) & (lengths <= 6))
        assert np.linalg.norm(demo.puck[-1] - demo.layout.goal) < 0.05
        assert len(demo.actions) % 2 == 0 and len(demo.states) == len(demo.actions) + 1
        assert np.all(np.abs(demo.actions) <= 1.0)
        for frame, subgoal in zip(demo.completions, demo.subgoals):
            assert np.linalg.norm(demo.puck[frame] - subgoal) < params.reach_tolerance
    assert {demo.side for demo in accepted} == {-1, 1}


def test_strict_bounds_reject(env):
    rng = np.random.default_rng(0)
    layout = env.task.sampler.sample(rng)
    assert run_demo(env, layout, rng, DemoParams(min_push_frames=7, max_push_frames=7)) is None


def test_default_timing_is_regular():
    speeds, pauses = draw_timing(np.random.default_rng(0), DemoParams())
    assert np.all(speeds == DemoParams.push_speed) and not pauses.any()


@pytest.fixture(scope="module")
def irregular():
    """dataset=pushing_irregular's generator and its first 12 accepted demos of seed 7."""
    with initialize_config_module(CONFIG_MODULE, version_base="1.3"):
        generator = instantiate(compose("generate", overrides=["dataset=pushing_irregular"]).dataset.generator)
    return generator, [generator.demo(index, seed=7)[0] for index in range(12)]


def test_irregular_push_lengths_spread_over_3_to_9_frames(irregular):
    generator, demos = irregular
    lengths = np.concatenate([demo.push_lengths(generator.frame_skip) for demo in demos])
    assert set(lengths.tolist()) == set(range(3, 10))  # every length of the range among these 72 pushes


def test_irregular_pauses_keep_the_puck_still_while_the_pusher_backs_away(irregular):
    generator, demos = irregular
    skip, contact = generator.frame_skip, generator.puck_radius + generator.pusher_radius
    assert {int(p) for demo in demos for p in demo.pauses[:-1]} == {0, 1, 2}
    assert all(demo.pauses[-1] == 0 for demo in demos)
    for demo in demos:
        saved = demo.saved_completions(skip)
        for push, pause in enumerate(demo.pauses):
            if not pause:
                continue
            paused = slice(demo.completions[push], (saved[push] + pause) * skip + 1)  # raw frames
            puck, pusher = demo.puck[paused], demo.pusher[paused]
            assert np.linalg.norm(puck - puck[0], axis=1).max() < generator.reach_tolerance
            distance = np.linalg.norm(pusher - puck, axis=1)
            assert distance[1:].min() > contact and distance[-1] > distance[0]  # in contact only as the push ends
            # The next push starts after the pause: its length does not count the pause.
            if push + 1 < len(saved):
                assert saved[push + 1] - saved[push] == pause + demo.push_lengths(skip)[push + 1]
