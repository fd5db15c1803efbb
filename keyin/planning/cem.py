"""Cross-entropy method with a diagonal Gaussian (paper Alg. 1, Alg. 4, App. 10).

Each iteration draws ``samples`` candidates from ``N(mean, std²)`` (independent per element),
clips them to the bounds, scores them with a cost function, and refits the mean and the
**population** standard deviation (ddof 0: one elite gives std 0, not NaN; docs/architecture.md, "Planning") of the
``elites`` lowest-cost candidates, the clipped values being the ones scored. The best candidate seen
in any iteration is returned. The candidates may have any shape ``(...)``, so the same functions
serve the servo's action sequences ``(l, 2)`` and a latent CEM over keyframe latents ``(L, Zk)``:
the cost function gets a numpy batch ``(n, ...)`` and returns ``n`` costs (numpy or anything
``np.asarray`` takes, e.g. a CPU torch tensor).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

CostFn = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class CEMParams:
    """Sampling budget and bounds; ``low``/``high`` None means unbounded (latents)."""

    samples: int = 200
    elites: int = 10
    iterations: int = 3
    low: float | None = None
    high: float | None = None
    min_std: float = 0.0  # std floor against premature collapse (docs/architecture.md, "Planning"); 0 = paper


@dataclass(frozen=True)
class CEMResult:
    """Outcome of :func:`cem`.

    Attributes:
        best: (...) lowest-cost candidate over all iterations.
        best_cost: its cost.
        mean, std: (...) the distribution after the last refit.
    """

    best: np.ndarray
    best_cost: float
    mean: np.ndarray
    std: np.ndarray


def sample_gaussian(
    mean: np.ndarray,
    std: np.ndarray,
    n: int,
    rng: np.random.Generator,
    low: float | None = None,
    high: float | None = None,
) -> np.ndarray:
    """(n, ...) draws from the diagonal Gaussian ``N(mean, std²)`` of shape (...), clipped to [low, high]."""
    mean = np.asarray(mean, dtype=np.float64)
    draws = mean + np.asarray(std, dtype=np.float64) * rng.standard_normal((n, *mean.shape))
    if low is None and high is None:
        return draws
    return np.clip(draws, low, high)


def elite_order(costs: np.ndarray) -> np.ndarray:
    """(n,) indices from lowest to highest cost; stable, NaN last."""
    return np.argsort(np.asarray(costs, dtype=np.float64), kind="stable")


def fit_elites(
    samples: np.ndarray, costs: np.ndarray, n_elites: int, min_std: float = 0.0
) -> tuple[np.ndarray, np.ndarray]:
    """Mean and population std (...) of the ``n_elites`` lowest-cost samples (n, ...), std >= ``min_std``."""
    elites = samples[elite_order(costs)[:n_elites]]
    return elites.mean(axis=0), np.maximum(elites.std(axis=0), min_std)


def cem(
    cost_fn: CostFn,
    mean: np.ndarray,
    std: np.ndarray,
    params: CEMParams,
    rng: np.random.Generator,
) -> CEMResult:
    """Minimise ``cost_fn`` over candidates shaped like ``mean`` (...).

    Args:
        cost_fn: (n, ...) candidates -> (n,) costs (lower is better; NaN counts as worst).
        mean, std: (...) the initial distribution (``std`` broadcastable to ``mean``).
        params: samples, elites, iterations, clipping bounds, std floor.
        rng: the only source of randomness.
    """
    if not 0 < params.elites <= params.samples or params.iterations < 1:
        raise ValueError(f"CEM needs 0 < elites <= samples and iterations >= 1, got {params}")
    mean = np.asarray(mean, dtype=np.float64)
    std = np.broadcast_to(np.asarray(std, dtype=np.float64), mean.shape)
    best, best_cost = mean, np.inf
    for _ in range(params.iterations):
        samples = sample_gaussian(mean, std, params.samples, rng, params.low, params.high)
        costs = np.asarray(cost_fn(samples), dtype=np.float64)
        if costs.shape != (params.samples,):
            raise ValueError(f"cost_fn must return ({params.samples},) costs, got shape {costs.shape}")
        first = elite_order(costs)[0]
        if costs[first] < best_cost:
            best, best_cost = samples[first], float(costs[first])
        mean, std = fit_elites(samples, costs, params.elites, params.min_std)
    return CEMResult(best=best, best_cost=best_cost, mean=mean, std=std)
