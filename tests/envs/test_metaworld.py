"""Meta-World's experts as a dataset: the phase labels read from each expert's if/elif chain, the
switch rule, the weld and observation fixes, and the clips (known answers, determinism, shapes)."""

import copy
import runpy
import sys
from pathlib import Path

import numpy as np
import pytest
from hydra import compose, initialize_config_module
from hydra.utils import instantiate

import keyin.data.metaworld as metaworld_data
from keyin.data.metaworld import MetaWorldGenerator
from keyin.data.sources import decoded_frames
from keyin.envs.metaworld import PhaseTracer, Timing, branch_lines, debounced_switches, expert, import_metaworld, make_env, run_episode


class ToyPolicy:
    """Phase 0 left of 0, 1 between 0 and 1, 2 beyond."""

    @staticmethod
    def _desired_pos(o_d):
        x = o_d[0]
        if x < 0:
            return -1.0
        elif x < 1:
            return 0.0
        else:
            return 1.0

    def get_action(self, obs):
        target = self._desired_pos(obs)
        obs[0] = 99.0  # edits its observation in place, as door-open's expert does
        return np.array([target, 0.0, 0.0, 0.5])


def test_branch_lines_number_the_if_elif_else_chain_in_order():
    lines = branch_lines(ToyPolicy._desired_pos)
    assert sorted(lines.values()) == [0, 1, 2]
    assert list(lines) == sorted(lines)  # the branches' first lines, top to bottom


def test_branch_lines_refuse_a_function_without_a_chain():
    def straight(o_d):
        return o_d

    with pytest.raises(ValueError, match="no top-level if/elif/else"):
        branch_lines(straight)


def test_phase_tracer_labels_each_call_and_leaves_the_observation_alone():
    tracer = PhaseTracer(ToyPolicy())
    for x, phase in [(-3.0, 0), (0.5, 1), (7.0, 2), (-0.1, 0)]:
        obs = np.array([x, 0.0])
        action, got = tracer(obs)
        assert got == phase and action[0] == [-1.0, 0.0, 1.0][phase]
        assert obs[0] == x


@pytest.mark.parametrize("phases, hold, switches", [
    ([0, 0, 1, 1, 1, 2, 2, 2], 3, [2, 5]),
    ([0, 0, 0, 1, 0, 0, 2, 2, 2, 2], 3, [6]),        # a one-step flicker is merged into the phase before
    ([0, 0, 0, 1, 1, 0, 0, 0], 2, [3, 5]),           # a phase held long enough counts, even when it returns
    ([0, 0, 0, 0], 3, []),
    ([1, 0, 0, 0, 0], 3, [1]),                       # a short first phase is still the first
])
def test_debounced_switches_known_answers(phases, hold, switches):
    assert debounced_switches(np.array(phases), hold) == switches


def test_weld_fix_writes_metaworlds_row_at_mujocos_width():
    import_metaworld()
    import mujoco

    env = make_env("push-v3", 50)
    welds = env.model.eq_data[env.model.eq_type == mujoco.mjtEq.mjEQ_WELD]
    assert welds.shape[1] == 12 and len(welds) >= 1
    np.testing.assert_array_equal(welds[0], [0, 0, 0, 0, 0, 0, -1, 0, 0, 0, 5, 0])
    assert import_metaworld() is import_metaworld()  # idempotent


def test_the_expert_sees_the_goal_and_solves_pick_place_as_shipped():
    env = make_env("pick-place-v3", 200)
    as_shipped = Timing(hand_low=None, hand_high=None, speed_min=1.0, max_pause=0)
    episode = run_episode(env, PhaseTracer(expert("pick-place-v3")), as_shipped, np.random.default_rng(0), 150, 0,
                          lambda e: None, 1000)
    assert episode.success_step is not None and episode.success_step < 100
    assert np.abs(env._get_obs()[-3:]).sum() > 0  # the goal in the observation is not clipped to 0
    assert debounced_switches(episode.phases, 3)[0] > 0


@pytest.fixture(scope="module")
def push_clip():
    generator = MetaWorldGenerator(tasks=("push-v3",), image_size=16)
    return generator, generator.generate(3, 11)


def test_clip_layout_labels_and_padding(push_clip):
    generator, (arrays, attempts) = push_clip
    length, valid = generator.clip_length, int(arrays["length"])
    assert arrays["frames"].shape == (length, 16, 16, 3) and arrays["frames"].dtype == np.uint8
    assert arrays["keyframes"].shape == (length,) and arrays["phases"].shape == (length,)
    assert 2 <= valid <= length and attempts >= 1
    keyframes = np.flatnonzero(arrays["keyframes"])
    assert 2 <= len(keyframes) <= 3 and keyframes[-1] == round(int(arrays["success_step"]) / generator.frame_skip)
    assert valid - 1 - keyframes[-1] <= generator.tail_frames
    assert (arrays["frames"][valid:] == arrays["frames"][valid - 1]).all()  # padding repeats the last frame
    assert arrays["frames"][0].std() > 10  # a rendered scene, not a blank
    assert (np.diff(arrays["phases"][:valid].astype(int)) != 0).sum() >= 1


def test_a_copy_of_the_physics_renders_as_the_env_did_when_it_was_taken(push_clip):
    """The generator renders a kept episode's saved frames afterwards, from copies of env.data."""
    generator = push_clip[0]
    env, tracer, renderer = generator.world("push-v3")
    obs, _ = env.reset()
    snapshots, direct = [], []
    for _ in range(3):
        for _ in range(generator.frame_skip):
            obs = env.step(tracer(obs)[0].astype(np.float32))[0]
        snapshots.append(copy.copy(env.data))
        direct.append(generator.render(renderer, env.data))
    later = [generator.render(renderer, data) for data in snapshots]
    assert all(np.array_equal(a, b) for a, b in zip(direct, later))
    assert not np.array_equal(later[0], later[-1])  # the copies are not one shared state


def test_clips_are_deterministic_in_seed_plus_index(push_clip):
    generator, (arrays, _) = push_clip
    again, _ = MetaWorldGenerator(tasks=("push-v3",), image_size=16).generate(3, 11)
    for key in arrays:
        np.testing.assert_array_equal(arrays[key], again[key])
    other, _ = generator.generate(4, 11)
    assert not np.array_equal(other["frames"], arrays["frames"])


def test_the_config_builds_the_generator():
    with initialize_config_module("keyin.conf", version_base="1.3"):
        config = compose("generate", overrides=["dataset=metaworld"])
    generator = instantiate(config.dataset.generator)
    assert generator.tasks == ("pick-place-v3", "push-v3", "door-open-v3", "drawer-open-v3", "button-press-topdown-v3")
    assert generator.clip_length == config.dataset.n_cond + config.dataset.n_future and hash(generator)


def test_unknown_task_is_named():
    with pytest.raises(ValueError, match="unknown Meta-World task 'pick-plaec-v3'"):
        make_env("pick-plaec-v3", 10)


def test_unknown_tasks_are_refused_with_the_known_ones():
    with pytest.raises(ValueError, match=r"unknown Meta-World task\(s\) \['pick-plaec-v3'\]; the tasks with an expert are \[.*'pick-place-v3'"):
        MetaWorldGenerator(tasks=("push-v3", "pick-plaec-v3"))


def test_a_missing_metaworld_install_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "metaworld", None)  # as if not installed
    with pytest.raises(ImportError, match=r"pip install 'metaworld==3.0.0' packaging \(or pip install 'keyin\[sim\]'\)"):
        import_metaworld()


@pytest.mark.slow  # five 256x256 episodes: ~14 s
def test_the_committed_example_episodes_are_what_their_script_writes(tmp_path):
    """docs/examples/metaworld: the same labels and frame counts, and frames within codec noise."""
    committed = Path(__file__).parents[2] / "docs" / "examples" / "metaworld"
    try:
        runpy.run_path(str(committed.parent / "metaworld_episodes.py"))["main"](tmp_path)
    finally:  # the script's 256x256 worlds are not kept for the tests after it
        for key in [key for key in metaworld_data._WORLDS if key[0].image_size == 256]:
            del metaworld_data._WORLDS[key]
    assert (tmp_path / "labels.csv").read_text() == (committed / "labels.csv").read_text()
    for video in sorted(committed.glob("*.mp4")):
        ours, theirs = (np.stack(list(decoded_frames(folder / video.name))) for folder in (committed, tmp_path))
        assert ours.shape == theirs.shape
        assert np.abs(ours.astype(int) - theirs).mean() < 2.0
