"""The generic CEM (keyin/planning/cem.py) on known quadratics."""

import numpy as np
import pytest

from keyin.planning.cem import CEMParams, cem, fit_elites, sample_gaussian


def quadratic(centre: np.ndarray):
    def cost(samples: np.ndarray) -> np.ndarray:
        return ((samples - centre) ** 2).reshape(len(samples), -1).sum(axis=1)

    return cost


def test_finds_the_minimum_of_a_quadratic():
    centre = np.array([[0.3, -0.5], [0.1, 0.7], [-0.2, 0.0]])
    params = CEMParams(samples=200, elites=10, iterations=8)
    result = cem(quadratic(centre), np.zeros((3, 2)), np.ones((3, 2)), params, np.random.default_rng(0))
    assert result.best.shape == (3, 2)
    np.testing.assert_allclose(result.best, centre, atol=0.05)
    np.testing.assert_allclose(result.mean, centre, atol=0.05)
    assert result.best_cost == pytest.approx(quadratic(centre)(result.best[None])[0])
    assert np.all(result.std < 0.1)


def test_clips_to_the_bounds():
    centre = np.array([2.0, -3.0, 0.5])
    seen = []

    def cost(samples):
        seen.append(samples)
        return quadratic(centre)(samples)

    params = CEMParams(samples=50, elites=5, iterations=4, low=-1.0, high=1.0)
    result = cem(cost, np.zeros(3), 1.0, params, np.random.default_rng(1))
    everything = np.concatenate(seen)
    assert everything.shape == (200, 3) and everything.min() >= -1.0 and everything.max() <= 1.0
    np.testing.assert_allclose(result.best, [1.0, -1.0, 0.5], atol=0.05)


def test_best_is_tracked_over_iterations_and_seeded():
    # A cost whose later iterations are all worse: the best of the first iteration is kept.
    calls = []

    def cost(samples):
        calls.append(samples)
        return np.full(len(samples), float(len(calls))) - (len(calls) == 1) * np.arange(len(samples)) * 1e-3

    params = CEMParams(samples=20, elites=4, iterations=3)
    result = cem(cost, np.zeros(2), np.ones(2), params, np.random.default_rng(2))
    np.testing.assert_array_equal(result.best, calls[0][-1])
    again = cem(quadratic(np.ones(2)), np.zeros(2), np.ones(2), params, np.random.default_rng(2))
    other = cem(quadratic(np.ones(2)), np.zeros(2), np.ones(2), params, np.random.default_rng(2))
    np.testing.assert_array_equal(again.best, other.best)


def test_population_std_and_floor():
    samples = np.array([[0.0], [2.0], [10.0]])
    mean, std = fit_elites(samples, np.array([1.0, 0.0, 5.0]), 2)
    assert mean[0] == 1.0 and std[0] == 1.0  # ddof 0
    _, single = fit_elites(samples, np.array([1.0, 0.0, 5.0]), 1, min_std=1e-3)
    assert single[0] == 1e-3  # one elite: std 0, not NaN, raised to the floor


def test_nan_costs_rank_last():
    samples = np.arange(4.0)[:, None]
    mean, _ = fit_elites(samples, np.array([np.nan, 3.0, np.nan, 1.0]), 2)
    assert mean[0] == 2.0


def test_sample_shape_and_bad_costs():
    draws = sample_gaussian(np.zeros((8, 2)), 0.5, 7, np.random.default_rng(0), -1.0, 1.0)
    assert draws.shape == (7, 8, 2)
    with pytest.raises(ValueError):
        cem(lambda s: np.zeros(3), np.zeros(2), 1.0, CEMParams(samples=5, elites=2), np.random.default_rng(0))
    with pytest.raises(ValueError):
        cem(quadratic(np.zeros(2)), np.zeros(2), 1.0, CEMParams(samples=5, elites=6), np.random.default_rng(0))
