"""attention_posterior (paper eq. 1-2; docs/architecture.md, "Padding and masking")."""

import math

import pytest
import torch

from keyin.models.attention import attention_posterior

BATCH, FRAMES, EMBED_DIM, LATENT_DIM = 4, 7, 6, 3


def make_inputs(seed: int = 0):
    generator = torch.Generator().manual_seed(seed)
    query = torch.randn(BATCH, EMBED_DIM, generator=generator, dtype=torch.float64)
    keys = torch.randn(BATCH, FRAMES, EMBED_DIM, generator=generator, dtype=torch.float64)
    values = torch.randn(BATCH, FRAMES, 2 * LATENT_DIM, generator=generator, dtype=torch.float64)
    lengths = torch.tensor([FRAMES, 3, 1, 0])
    mask = torch.arange(FRAMES) < lengths[:, None]
    return query, keys, values, mask


@pytest.mark.parametrize("scale", [False, True])
def test_matches_brute_force(scale):
    query, keys, values, mask = make_inputs()
    inv_temperature = torch.tensor(1.7, dtype=torch.float64)

    mu, log_sigma, weights = attention_posterior(query, keys, values, mask, inv_temperature, scale)

    assert mu.shape == log_sigma.shape == (BATCH, LATENT_DIM)
    assert weights.shape == (BATCH, FRAMES)
    for row in range(BATCH):
        valid = [j for j in range(FRAMES) if mask[row, j]]
        factor = 1.7 / math.sqrt(EMBED_DIM) if scale else 1.7
        exps = {j: math.exp(factor * float(query[row] @ keys[row, j])) for j in valid}
        total = sum(exps.values())
        expected_weights = torch.zeros(FRAMES, dtype=torch.float64)
        expected_params = torch.zeros(2 * LATENT_DIM, dtype=torch.float64)
        for j in valid:
            expected_weights[j] = exps[j] / total
            expected_params += expected_weights[j] * values[row, j]
        torch.testing.assert_close(weights[row], expected_weights)
        torch.testing.assert_close(mu[row], expected_params[:LATENT_DIM])
        torch.testing.assert_close(log_sigma[row], expected_params[LATENT_DIM:])


def test_weights_sum_to_one_over_valid_and_vanish_elsewhere():
    query, keys, values, mask = make_inputs()

    _, _, weights = attention_posterior(query, keys, values, mask, 1.0, True)

    torch.testing.assert_close(weights.sum(-1)[mask.any(-1)], torch.ones(3, dtype=torch.float64))
    assert (weights[~mask] == 0).all()
    assert (weights[mask] > 0).all()


def test_all_masked_row_gives_zeros_and_finite_gradients():
    query, keys, values, mask = make_inputs()
    query.requires_grad_(True)
    keys.requires_grad_(True)
    values.requires_grad_(True)
    inv_temperature = torch.tensor(1.0, dtype=torch.float64, requires_grad=True)

    mu, log_sigma, weights = attention_posterior(query, keys, values, mask, inv_temperature, True)
    (mu.sum() + log_sigma.sum() + (weights * torch.arange(FRAMES)).sum()).backward()

    assert not mask[3].any()
    assert torch.isfinite(mu).all() and torch.isfinite(log_sigma).all() and torch.isfinite(weights).all()
    assert (weights[3] == 0).all() and (mu[3] == 0).all() and (log_sigma[3] == 0).all()
    for tensor in (query, keys, values, inv_temperature):
        assert torch.isfinite(tensor.grad).all()
    assert query.grad[0].abs().sum() > 0 and inv_temperature.grad != 0


def test_masked_values_and_keys_do_not_matter():
    query, keys, values, mask = make_inputs()
    mu, log_sigma, weights = attention_posterior(query, keys, values, mask, 1.0, True)

    changed_keys = torch.where(mask[..., None], keys, 100.0)
    changed_values = torch.where(mask[..., None], values, 100.0)
    changed = attention_posterior(query, changed_keys, changed_values, mask, 1.0, True)

    torch.testing.assert_close(changed, (mu, log_sigma, weights))


def entropy(weights):
    return -(weights * weights.clamp_min(1e-12).log()).sum(-1)


def test_inverse_temperature_sharpens_and_scale_divides_by_sqrt_dim():
    query, keys, values, mask = make_inputs()

    _, _, soft = attention_posterior(query, keys, values, mask, torch.tensor(0.5), True)
    _, _, sharp = attention_posterior(query, keys, values, mask, torch.tensor(5.0), True)
    _, _, scaled = attention_posterior(query, keys, values, mask, math.sqrt(EMBED_DIM), True)
    _, _, unscaled = attention_posterior(query, keys, values, mask, 1.0, False)

    assert (entropy(sharp)[:2] < entropy(soft)[:2]).all()  # rows with more than one valid frame
    torch.testing.assert_close(scaled, unscaled)
    assert not torch.allclose(unscaled, attention_posterior(query, keys, values, mask, 1.0, True)[2])
