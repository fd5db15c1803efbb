"""Interpolator and InterpolatorPosterior (paper §3.1-3.2)."""

import pytest
import torch
import torch.nn.functional as F

from keyin.models.interpolator import Interpolator, InterpolatorPosterior

ROWS, EMBED_DIM, MAX_OFFSET, LATENT_DIM, HIDDEN, LAYERS, MLP_HIDDEN = 5, 6, 4, 3, 16, 2, 16
STEP_INPUTS = ["boundaries", "autoregressive"]


def make_segments(seed: int = 0):
    generator = torch.Generator().manual_seed(seed)
    start = torch.rand(ROWS, EMBED_DIM, generator=generator) * 2 - 1
    end = torch.rand(ROWS, EMBED_DIM, generator=generator) * 2 - 1
    offset_probs = torch.softmax(torch.randn(ROWS, MAX_OFFSET, generator=generator), -1)
    z = torch.randn(ROWS, LATENT_DIM, generator=generator)
    return start, end, offset_probs, z


def make_interpolator(step_input: str, latent_dim: int = LATENT_DIM) -> Interpolator:
    torch.manual_seed(0)
    return Interpolator(EMBED_DIM, MAX_OFFSET, latent_dim, HIDDEN, LAYERS, MLP_HIDDEN, step_input)


@pytest.mark.parametrize("step_input", STEP_INPUTS)
def test_output_shape_and_range(step_input):
    interpolator = make_interpolator(step_input)

    frames = interpolator(*make_segments())

    assert frames.shape == (ROWS, MAX_OFFSET, EMBED_DIM)
    assert frames.abs().max() < 1


@pytest.mark.parametrize("step_input", STEP_INPUTS)
def test_latent_is_used(step_input):
    interpolator = make_interpolator(step_input)
    start, end, offset_probs, z = make_segments()

    frames = interpolator(start, end, offset_probs, z)
    assert not torch.allclose(frames, interpolator(start, end, offset_probs, -z))
    with pytest.raises(ValueError, match="z must have shape"):
        interpolator(start, end, offset_probs)


@pytest.mark.parametrize("step_input", STEP_INPUTS)
def test_zero_latent_dim_is_deterministic_without_latent_input(step_input):
    interpolator = make_interpolator(step_input, latent_dim=0)
    start, end, offset_probs, z = make_segments()

    first = interpolator(start, end, offset_probs)
    second = interpolator(start, end, offset_probs, torch.zeros(ROWS, 0))

    torch.testing.assert_close(first, second)
    assert interpolator.init_mlp.network[0].in_features == 2 * EMBED_DIM + MAX_OFFSET
    with pytest.raises(ValueError, match="deterministic"):
        interpolator(start, end, offset_probs, z)


@pytest.mark.parametrize("step_input", STEP_INPUTS)
def test_gradients_reach_boundaries_offsets_and_latent(step_input):
    interpolator = make_interpolator(step_input)
    inputs = [tensor.requires_grad_(True) for tensor in make_segments()]

    interpolator(*inputs).pow(2).sum().backward()

    for tensor in inputs:
        assert tensor.grad is not None and tensor.grad.abs().sum() > 0
    assert all(param.grad is not None for param in interpolator.parameters())


def test_only_boundaries_steps_read_end_and_offsets_directly():
    """Only the boundaries input gives every step direct access to the end keyframe and the offsets."""
    start, end, offset_probs, z = make_segments()
    for step_input, expect_change in (("autoregressive", False), ("boundaries", True)):
        interpolator = make_interpolator(step_input)
        with torch.no_grad():
            interpolator.init_mlp.network[-1].weight.zero_()  # the initial state ignores its inputs
        first = interpolator(start, end, offset_probs, z)
        other_end = interpolator(start, -end, offset_probs, z)
        other_offsets = interpolator(start, end, offset_probs.flip(-1), z)
        assert (not torch.allclose(first, other_end)) == expect_change
        assert (not torch.allclose(first, other_offsets)) == expect_change


def test_invalid_step_input_raises():
    with pytest.raises(ValueError, match="step_input"):
        Interpolator(EMBED_DIM, MAX_OFFSET, 0, HIDDEN, LAYERS, MLP_HIDDEN, "teacher_forcing")


def test_posterior_reads_the_last_valid_step():
    torch.manual_seed(0)
    posterior = InterpolatorPosterior(EMBED_DIM, LATENT_DIM, HIDDEN)
    targets = torch.randn(ROWS, MAX_OFFSET, EMBED_DIM)
    offsets = torch.tensor([1, 2, 3, 4, 2])
    mask = torch.arange(MAX_OFFSET) < offsets[:, None]

    mu, log_sigma = posterior(targets, mask)
    padded = torch.where(mask[..., None], targets, torch.randn_like(targets))
    padded_mu, padded_log_sigma = posterior(padded, mask)
    changed_last = targets.clone()
    changed_last[torch.arange(ROWS), offsets - 1] += 1.0
    changed_mu, _ = posterior(changed_last, mask)

    assert mu.shape == log_sigma.shape == (ROWS, LATENT_DIM)
    torch.testing.assert_close(padded_mu, mu)
    torch.testing.assert_close(padded_log_sigma, log_sigma)
    assert not torch.isclose(changed_mu, mu).all(dim=-1).any()  # every row reads its last valid step
    single_mu, _ = posterior(targets[1:2, :2], mask[1:2, :2])  # the same segment without padding
    torch.testing.assert_close(single_mu, mu[1:2])


def test_posterior_needs_a_latent():
    with pytest.raises(ValueError, match="latent_dim"):
        InterpolatorPosterior(EMBED_DIM, 0, HIDDEN)


@pytest.fixture
def single_thread():
    """Tiny matrices: a second intra-op thread only adds synchronisation (10× slower on a busy CPU)."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


def test_boundaries_interpolator_learns_linear_interpolation_at_every_offset(single_thread):
    """Frame i of a segment with offset o is start + (i+1)/o · (end − start)."""
    torch.manual_seed(0)
    embed_dim, max_offset = 4, 6
    interpolator = Interpolator(embed_dim, max_offset, 0, 32, 1, 32, "boundaries", mlp_layers=2)
    optimizer = torch.optim.Adam(interpolator.parameters(), lr=1e-2)
    steps = torch.arange(max_offset)

    def segments(rows: int):
        start = torch.rand(rows, embed_dim) * 1.6 - 0.8
        end = torch.rand(rows, embed_dim) * 1.6 - 0.8
        offsets = torch.randint(1, max_offset + 1, (rows,))
        fraction = ((steps + 1) / offsets[:, None]).clamp(max=1)  # (rows, S)
        targets = start[:, None] + fraction[..., None] * (end - start)[:, None]
        offset_probs = F.one_hot(offsets - 1, max_offset).float()
        return start, end, offset_probs, targets, offsets

    for _ in range(150):
        start, end, offset_probs, targets, offsets = segments(64)
        squared_error = (interpolator(start, end, offset_probs) - targets).pow(2).sum(-1)
        loss = squared_error[steps < offsets[:, None]].mean()
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()

    with torch.no_grad():
        start, end, offset_probs, targets, offsets = segments(1000)
        squared_error = (interpolator(start, end, offset_probs) - targets).pow(2).sum(-1)
        copy_error = (start[:, None] - targets).pow(2).sum(-1)
    for offset in range(1, max_offset + 1):
        rows = offsets == offset
        error = squared_error[rows, :offset].mean()
        assert error < 0.03, f"offset {offset}: squared error {error:.3f}"
        assert error < 0.05 * copy_error[rows, :offset].mean()


def test_interpolate_segments_draws_z_as_asked_and_refuses_an_unknown_latent():
    from keyin.models.interpolator import interpolate_segments

    torch.manual_seed(0)
    interpolator = Interpolator(embed_dim=4, max_offset=3, latent_dim=2, hidden=8, layers=1, mlp_hidden=8)
    posterior = InterpolatorPosterior(embed_dim=4, latent_dim=2, hidden=8)
    embeddings, segments = torch.randn(2, 6, 4), (torch.tensor([0, 1]), torch.tensor([0, 2]), torch.tensor([3, 2]))
    predicted, valid, stats = interpolate_segments(interpolator, posterior, embeddings, *segments, "posterior")
    assert predicted.shape == (2, 3, 4) and valid.tolist() == [[True] * 3, [True, True, False]]
    assert stats is not None and stats[0].shape == (2, 2)
    mean, _, none = interpolate_segments(interpolator, posterior, embeddings, *segments, "mean")
    zero = interpolator(embeddings[[0, 1], [0, 2]], embeddings[[0, 1], [3, 4]], torch.eye(3)[[2, 1]], torch.zeros(2, 2))
    assert none is None and torch.allclose(mean, zero)
    with pytest.raises(ValueError, match="latent must be one of"):
        interpolate_segments(interpolator, posterior, embeddings, *segments, "median")
