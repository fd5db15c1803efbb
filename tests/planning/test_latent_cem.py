"""KEYIN's latent CEM (keyin/planning/latent_cem.py): the search on a stub keyframe renderer whose
pucks sit where z puts them, the prior-mode renderer of a stage-2 model, and the planner built from
a checkpoint."""

import pickle

import numpy as np
import pytest
import torch

from keyin.envs.segmentation import PUCK_RGB
from keyin.errors import CheckpointError
from keyin.planning.cem import CEMParams
from keyin.planning.latent_cem import LatentCEMSubgoals, PriorKeyframes, plan_keyframes
from keyin.planning.servo import subgoal_pixels
from tests.planning.trained_models import KEY_LATENT, KEYFRAMES, SIZE, keyframe_module, save

LATENT_SHAPE = (3, 3)  # (L, Zk)
THREADS = torch.get_num_threads()  # the planner sets torch's threads: keep the test process's


def disc_images(centres: np.ndarray, size: int = 32) -> np.ndarray:
    """(..., 2) (column, row) centres -> (..., size, size, 3) uint8: a puck of radius 3 on white."""
    rows, cols = np.mgrid[:size, :size] + 0.5
    inside = (cols - centres[..., 0, None, None]) ** 2 + (rows - centres[..., 1, None, None]) ** 2 <= 9
    images = np.full((*inside.shape, 3), 255, np.uint8)
    images[inside] = np.rint(np.array(PUCK_RGB) * 255)
    return images


def stub_renderer(scored: list, hidden=lambda z: np.zeros(z.shape[:-1], bool)):
    """Keyframe t shows the puck at pixel 16 + 4 z^t[:2] (off the image where ``hidden`` says); the
    latents the cost scored are appended to ``scored``."""

    def render(z: np.ndarray, last_only: bool) -> np.ndarray:
        centres = np.where(hidden(z)[..., None], -100.0, 16 + 4 * z[..., :2])  # (n, L, 2)
        images = disc_images(centres)
        if last_only:
            scored.append(z)
            return images[:, -1:]
        return images

    return render


def test_finds_the_latents_that_put_the_last_puck_on_the_goal():
    scored = []
    goal = disc_images(np.array([22.0, 10.0]))  # z^L[:2] = (1.5, -1.5)
    params = CEMParams(samples=200, elites=10, iterations=5)
    plan = plan_keyframes(stub_renderer(scored), goal, LATENT_SHAPE, params, np.random.default_rng(0))
    assert len(scored) == 5 and all(z.shape == (200, *LATENT_SHAPE) for z in scored)
    np.testing.assert_allclose(plan.z[-1, :2], [1.5, -1.5], atol=0.15)
    assert plan.cost < 1.0 and plan.samples_without_puck == 0
    assert plan.keyframes.shape == (3, 32, 32, 3) and plan.keyframes.dtype == np.uint8
    np.testing.assert_array_equal(plan.keyframes, stub_renderer([])(plan.z[None], False)[0])  # the best z's
    assert plan.cost == pytest.approx(np.linalg.norm(subgoal_pixels(plan.keyframes[-1:])[0] - [22.0, 10.0]), abs=0.3)


def test_a_last_keyframe_without_a_puck_costs_the_diagonal_and_is_counted():
    scored = []
    hidden = lambda z: np.broadcast_to(z[:, -1:, 0] > 0, z.shape[:-1])  # noqa: E731
    goal = disc_images(np.array([20.0, 16.0]))  # z^L[0] = 1: just past the hidden half
    params = CEMParams(samples=50, elites=5, iterations=3)
    plan = plan_keyframes(stub_renderer(scored, hidden), goal, LATENT_SHAPE, params, np.random.default_rng(1))
    assert plan.samples_without_puck == sum(int((z[:, -1, 0] > 0).sum()) for z in scored) > 0
    assert plan.z[-1, 0] <= 0 and plan.cost < 4.5  # the nearest visible pucks, not a hidden one

    nowhere = plan_keyframes(stub_renderer([], lambda z: np.ones(z.shape[:-1], bool)), goal, LATENT_SHAPE,
                             params, np.random.default_rng(1))
    assert nowhere.cost == pytest.approx(np.hypot(32, 32)) and nowhere.samples_without_puck == 150


def test_a_goal_without_a_puck_is_refused():
    with pytest.raises(ValueError, match="goal image shows no puck"):
        plan_keyframes(stub_renderer([]), np.full((32, 32, 3), 255, np.uint8), LATENT_SHAPE, CEMParams(8, 2, 1),
                       np.random.default_rng(0))


def test_prior_keyframes_are_deterministic_given_z_and_independent_of_the_batch():
    render = PriorKeyframes(keyframe_module().eval().model, disc_images(np.array([8.0, 8.0]), SIZE))
    z = np.random.default_rng(0).standard_normal((5, KEYFRAMES, KEY_LATENT))
    keyframes = render(z, False)
    assert keyframes.shape == (5, KEYFRAMES, SIZE, SIZE, 3) and keyframes.dtype == np.uint8
    np.testing.assert_array_equal(render(z, False), keyframes)
    np.testing.assert_array_equal(render(z[2:4], False), keyframes[2:4])
    np.testing.assert_array_equal(render(z, True), keyframes[:, -1:])


def planner(checkpoint: str, model: str = "keyin") -> LatentCEMSubgoals:
    return LatentCEMSubgoals(checkpoint, model, "pushing", f"keyin-train model={model}", THREADS, samples=8,
                             elites=2, iterations=2)


def test_the_planner_proposes_the_models_keyframes_the_same_for_the_same_seed(tmp_path):
    checkpoint = save(keyframe_module(), tmp_path / "keyin.ckpt", "keyin")
    start, goal = disc_images(np.array([[4.0, 4.0], [12.0, 12.0]]), SIZE)
    first = planner(checkpoint)(start, goal, None, np.random.default_rng(3))
    again = planner(checkpoint)(start, goal, None, np.random.default_rng(3))
    assert first.images.shape == (KEYFRAMES, SIZE, SIZE, 3) and first.images.dtype == np.uint8
    assert set(first.diagnostics) == {"plan_cost_px", "plan_samples_without_puck"}
    assert 0 <= first.diagnostics["plan_samples_without_puck"] <= 16
    assert 0 <= first.diagnostics["plan_cost_px"] <= np.hypot(SIZE, SIZE)
    np.testing.assert_array_equal(first.images, again.images)
    assert first.diagnostics == again.diagnostics


def test_the_model_is_loaded_once_per_process_and_not_pickled(tmp_path):
    built = planner(save(keyframe_module(), tmp_path / "keyin.ckpt", "keyin"))
    shipped = pickle.dumps(built)  # what the runner sends a spawn worker with every task
    assert len(shipped) < 1000
    assert pickle.loads(shipped).module() is built.module() and not built.module().training


@pytest.mark.parametrize("saved_as,message", [
    (None, "does not exist"),
    (("jumpy", "pushing"), "holds a model=jumpy dataset=pushing checkpoint"),
    (("keyin", "brownian"), "holds a model=keyin dataset=brownian checkpoint"),
])
def test_a_missing_or_foreign_checkpoint_names_the_file_and_the_command(tmp_path, saved_as, message):
    path = tmp_path / "last.ckpt"
    if saved_as:
        save(keyframe_module(), path, *saved_as)
    with pytest.raises(CheckpointError, match=message) as err:
        planner(str(path))
    assert str(path) in str(err.value) and "`keyin-train model=keyin`" in str(err.value)
