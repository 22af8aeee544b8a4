"""Maximum marginal likelihood hyperparameters of the optimiser's Gaussian processes, in numpy
with analytic gradients.

The model is BoTorch's `SingleTaskGP` with its default priors (an RBF kernel with one
lengthscale per input, a log-normal prior on each, a log-normal prior on the noise, a constant
mean), one independent GP per output; `acquisition.fit_hyperparameters` reads the priors,
bounds and starting values from the model and writes the fitted values back into it. The
objective is gpytorch's `ExactMarginalLogLikelihood` (priors included, divided by the number of
observations), which a test checks value for value and gradient for gradient. Computed here it
costs a fraction of gpytorch's autograd for these small matrices (n up to a few hundred),
which made the GP fit most of the optimiser's time per trial.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

LOG_2PI = math.log(2 * math.pi)


@dataclass(frozen=True)
class LogNormal:
    """A log-normal prior (`loc`, `scale` of the underlying normal)."""

    loc: float
    scale: float

    def log_density(self, values: np.ndarray) -> tuple[float, np.ndarray]:
        """The summed log density at positive `values` and its gradient."""
        logs = np.log(values)
        standard = (logs - self.loc) / self.scale
        total = float(np.sum(-logs - math.log(self.scale) - 0.5 * LOG_2PI - 0.5 * standard**2))
        return total, (-1.0 - standard / self.scale) / values


@dataclass(frozen=True)
class Hyperparameters:
    """One output's hyperparameters: `d` lengthscales, the noise variance and the constant mean."""

    lengthscales: np.ndarray
    noise: float
    constant: float

    def vector(self) -> np.ndarray:
        return np.concatenate([self.lengthscales, [self.noise, self.constant]])

    @classmethod
    def from_vector(cls, vector: np.ndarray) -> "Hyperparameters":
        return cls(np.array(vector[:-2]), float(vector[-2]), float(vector[-1]))


def squared_differences(inputs: np.ndarray) -> np.ndarray:
    """`n x n x d` squared differences of `n x d` points, coordinate by coordinate."""
    return np.square(inputs[:, None, :] - inputs[None, :, :])


def negative_log_likelihood(
    vector: np.ndarray, differences: np.ndarray, targets: np.ndarray, lengthscale_prior: LogNormal, noise_prior: LogNormal
) -> tuple[float, np.ndarray]:
    """gpytorch's negative `ExactMarginalLogLikelihood` of one output and its gradient.

    Args:
        vector: `d + 2` hyperparameters (`Hyperparameters.vector`).
        differences: `n x n x d` `squared_differences` of the inputs.
        targets: `n` observations (standardised).

    Returns:
        (minus the log marginal likelihood plus log priors, divided by n; its `d + 2` gradient).
    """
    parameters = Hyperparameters.from_vector(vector)
    count, dimensions = len(targets), differences.shape[-1]
    scaled = (differences / np.square(parameters.lengthscales)).reshape(count * count, dimensions)
    correlation = np.exp(-0.5 * scaled.sum(axis=-1)).reshape(count, count)
    try:
        factor = np.linalg.cholesky(correlation + parameters.noise * np.eye(count))
    except np.linalg.LinAlgError:  # not numerically positive definite: L-BFGS-B's line search steps back
        return np.inf, np.zeros_like(vector)
    inverse_factor = _lower_triangular_inverse(factor)
    inverse = inverse_factor.T @ inverse_factor
    residual = targets - parameters.constant
    weights = inverse @ residual
    log_likelihood = -0.5 * residual @ weights - np.sum(np.log(np.diag(factor))) - 0.5 * count * LOG_2PI
    lengthscale_log_prior, lengthscale_prior_gradient = lengthscale_prior.log_density(parameters.lengthscales)
    noise_log_prior, noise_prior_gradient = noise_prior.log_density(np.array([parameters.noise]))
    # d(log likelihood)/dK = (w w^T - K^-1) / 2
    sensitivity = 0.5 * (np.outer(weights, weights) - inverse)
    lengthscale_gradient = ((sensitivity * correlation).reshape(-1) @ scaled) / parameters.lengthscales
    gradient = np.concatenate([lengthscale_gradient + lengthscale_prior_gradient, [np.trace(sensitivity) + noise_prior_gradient[0], np.sum(weights)]])
    return -(log_likelihood + lengthscale_log_prior + noise_log_prior) / count, -gradient / count


def maximise_likelihood(
    differences: np.ndarray,
    targets: np.ndarray,
    start: Hyperparameters,
    lower: np.ndarray,
    lengthscale_prior: LogNormal,
    noise_prior: LogNormal,
    iterations: int,
) -> Hyperparameters:
    """The hyperparameters of one output maximising its marginal likelihood and priors
    (L-BFGS-B from `start`, at most `iterations`), each at least its `lower` (`d + 2`; -inf
    for none); `differences` are the `squared_differences` of the inputs, which the outputs of
    one model share. The result depends on BLAS's thread count (OpenBLAS's triangular solve
    rounds differently with more threads): `acquisition.fit_hyperparameters` calls it on one."""
    from scipy.optimize import minimize

    bounds = [(None if np.isinf(bound) else float(bound), None) for bound in lower]
    result = minimize(
        negative_log_likelihood,
        start.vector(),
        args=(differences, targets, lengthscale_prior, noise_prior),
        jac=True,
        method="L-BFGS-B",
        bounds=bounds,
        options={"maxiter": iterations},
    )
    return Hyperparameters.from_vector(result.x) if np.all(np.isfinite(result.x)) else start


def _lower_triangular_inverse(factor: np.ndarray) -> np.ndarray:
    from scipy.linalg import solve_triangular

    return solve_triangular(factor, np.eye(len(factor)), lower=True)
