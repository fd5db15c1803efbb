"""The Surprise planner: SVG-FP prior rollouts that continue the model's own training recursion, the
surprise keyframes of the produced sequence as subgoals, and the latent CEM shared with KEYIN."""

import numpy as np
import pytest
import torch

from keyin.decode.surprise import surprise_keyframes
from keyin.planning.surprise_cem import SurpriseRollouts, SurpriseSubgoals
from keyin.planning.trained import images_to_tensor, tensor_to_images
from tests.planning.test_latent_cem import THREADS, disc_images
from tests.planning.trained_models import KEYFRAMES, SIZE, save, surprise_module

HORIZON, LATENT = 6, 2  # the module's n_future and latent size


def rollouts(skips: bool = False) -> SurpriseRollouts:
    return SurpriseRollouts(surprise_module(skips).eval().model, disc_images(np.array([8.0, 8.0]), SIZE), KEYFRAMES, -1)


def test_a_rollout_is_the_predictor_fed_its_own_predictions():
    render = rollouts()
    z = torch.randn(4, HORIZON, LATENT, generator=torch.Generator().manual_seed(0))
    predicted = render.model.rollout(render.cond_emb, z)  # (4, T, E)
    inputs = torch.cat([render.cond_emb.expand(4, -1, -1), predicted[:, :-1]], 1)  # e_0, ê_1 … ê_{T-1}
    with torch.no_grad():
        outputs, _ = render.model.core.predictor(torch.cat([inputs, z], -1))
    torch.testing.assert_close(predicted, torch.tanh(outputs))


@pytest.mark.parametrize("skips", [False, True])
def test_the_subgoals_are_the_decoded_frames_at_the_surprise_keyframes_of_the_rollout(skips):
    render = rollouts(skips)
    z = np.random.default_rng(1).standard_normal((3, HORIZON, LATENT))
    subgoals = render(z, False)
    assert subgoals.shape == (3, KEYFRAMES, SIZE, SIZE, 3) and subgoals.dtype == np.uint8
    model = render.model
    with torch.no_grad():
        start = images_to_tensor(disc_images(np.array([8.0, 8.0]), SIZE), model.encoder.image_shape)
        _, context = model.encode(start[None, None])  # with skips: the start frame's encoder features
        embeddings = model.rollout(render.cond_emb, torch.as_tensor(z, dtype=torch.float32))
        frames = torch.sigmoid(model.decode(embeddings, context))
        kl = model.surprise(torch.cat([start.expand(3, 1, -1, -1, -1), frames], 1))
    positions = surprise_keyframes(kl, torch.full((3,), HORIZON), 1, KEYFRAMES, shift=-1)
    for row, picked in enumerate(positions):
        np.testing.assert_array_equal(subgoals[row], tensor_to_images(frames[row, picked]))
    last = render(z, True)
    np.testing.assert_array_equal(last[:, 0], tensor_to_images(frames[:, -1]))  # the cost's frame


def test_the_planner_is_deterministic_for_a_seed(tmp_path):
    checkpoint = save(surprise_module(), tmp_path / "surprise.ckpt", "surprise")
    planner = SurpriseSubgoals(checkpoint, "surprise", "pushing", "keyin-train model=surprise", THREADS, samples=8,
                               elites=2, iterations=2)
    start, goal = disc_images(np.array([[4.0, 4.0], [12.0, 12.0]]), SIZE)
    first, again = (planner(start, goal, None, np.random.default_rng(3)) for _ in range(2))
    assert first.images.shape == (KEYFRAMES, SIZE, SIZE, 3)
    assert set(first.diagnostics) == {"plan_cost_px", "plan_samples_without_puck"}
    np.testing.assert_array_equal(first.images, again.images)
    assert first.diagnostics == again.diagnostics
