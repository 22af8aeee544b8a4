"""Where to try next: scrambled Sobol points for the initial trials, uniform random points for
the baseline, and BoTorch acquisition maximisation on a GP fitted to (parameters, robustness).

BoTorch and torch are imported inside the functions: they cost about 2 s to import, which
commands that never optimise should not pay.
"""

from __future__ import annotations

import warnings
from contextlib import contextmanager
from typing import Iterator

import numpy as np

from stl_lfd.optim.likelihood import Hyperparameters, LogNormal, maximise_likelihood, squared_differences

ACQUISITION_RESTARTS = 8
RAW_SAMPLES = 256
# L-BFGS-B iterations of the GP hyperparameter fit (per output): 100 reached a marginal log
# likelihood within 0.001 of the converged one at n = 30, d = 21 (measured with gpytorch's fit,
# which the numpy likelihood replaced; the objective is the same).
FIT_ITERATIONS = 100
# L-BFGS-B iterations of each acquisition restart. BoTorch's default (200) spent 2-3 s per
# PI proposal on phi2-shaped problems alone (8-15 s beside another run; flat log-PI, ~750
# evaluations); with 60 the maximum found was within 3.5 % of its PI (checked on a phi2
# history) in half the time.
ACQUISITION_ITERATIONS = 60
# SINGLE_THREAD: these matrices are tiny (n <= a few hundred), so one thread is as fast as two,
# and it avoids OpenMP threads spinning against the simulator or a parallel run on 2 cores
# (measured: proposals 30x slower with two runs side by side). BLAS too, for reproducibility:
# OpenBLAS's triangular solve rounds differently with more threads, the GP fit's L-BFGS-B
# magnifies that, and the same seed gave other trials on a machine with another core count.


def sobol_points(bounds: np.ndarray, count: int, seed: int) -> np.ndarray:
    """`count x d` scrambled Sobol points inside `bounds` (`2 x d`), the same for the same seed."""
    from torch.quasirandom import SobolEngine

    unit = SobolEngine(bounds.shape[1], scramble=True, seed=seed).draw(count, dtype=_float64()).numpy()
    return bounds[0] + unit * (bounds[1] - bounds[0])


def random_point(bounds: np.ndarray, seed: int, trial: int) -> np.ndarray:
    """A uniform point inside `bounds`, determined by the seed and the trial number alone."""
    unit = np.random.default_rng([seed, trial]).random(bounds.shape[1])
    return bounds[0] + unit * (bounds[1] - bounds[0])


def propose(X: np.ndarray, Y: np.ndarray, bounds: np.ndarray, method: str, xi: float, seed: int) -> np.ndarray:
    """The maximiser of the acquisition function on a GP fitted to the observations.

    Args:
        X: `n x d` observed points.
        Y: `n` robustness values.
        bounds: `2 x d`.
        method: `pi` (probability of improvement, as in the paper) or `logei`.
        xi: PI's margin, in standard deviations of the observed robustness: improvement means
            exceeding max(Y) + xi * std(Y). Without it PI saturates and over-exploits.
        seed: seeds the random starts of the acquisition optimiser.

    Returns:
        `d` next point.
    """
    import torch

    torch.manual_seed(seed)
    with single_threaded():
        return _maximise(X, Y, bounds, method, xi, seed)


@contextmanager
def single_threaded() -> Iterator[None]:
    """Torch and BLAS on one thread for the block (see SINGLE_THREAD), restored afterwards."""
    import scipy.linalg  # noqa: F401 (loaded before the limit, which only reaches loaded libraries)
    import torch
    from threadpoolctl import threadpool_limits

    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        with threadpool_limits(limits=1, user_api="blas"):
            yield
    finally:
        torch.set_num_threads(threads)


def _maximise(X: np.ndarray, Y: np.ndarray, bounds: np.ndarray, method: str, xi: float, seed: int) -> np.ndarray:
    from botorch.acquisition.analytic import LogExpectedImprovement, LogProbabilityOfImprovement

    model = fit_gp(X, Y, bounds)
    best = float(np.max(Y))
    if method == "pi":
        acquisition = LogProbabilityOfImprovement(model, best_f=best + xi * float(np.std(Y)))
    elif method == "logei":
        acquisition = LogExpectedImprovement(model, best_f=best)
    else:
        raise ValueError(f"unknown acquisition {method!r}")
    candidate = maximise_acquisition(acquisition, bounds, ACQUISITION_RESTARTS, RAW_SAMPLES, seed, ACQUISITION_ITERATIONS)
    return np.clip(candidate, bounds[0], bounds[1])


def maximise_acquisition(acquisition, box: np.ndarray, restarts: int, raw_samples: int, seed: int, iterations: int | None = None, starts=None) -> np.ndarray:
    """The maximiser (`d`) of a q = 1 acquisition function inside `box` (`2 x d`): BoTorch's
    multi-start L-BFGS-B, `iterations` per restart (None: BoTorch's default), from `restarts`
    starts chosen among `raw_samples` random points, plus the `k x 1 x d` tensor `starts` if
    given."""
    import torch
    from botorch.optim import optimize_acqf

    options = {"seed": seed} | ({"maxiter": iterations} if iterations is not None else {})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # restarts that end on flat regions warn
        candidate, _ = optimize_acqf(
            acquisition,
            bounds=torch.as_tensor(box, dtype=torch.float64),
            q=1,
            num_restarts=restarts + (0 if starts is None else len(starts)),
            raw_samples=raw_samples,
            options=options,
            batch_initial_conditions=starts,
        )
    return candidate.detach().numpy()[0]


def fit_gp(X: np.ndarray, Y: np.ndarray, bounds: np.ndarray):
    """A `SingleTaskGP` (inputs normalised to the bounds, outputs standardised) fitted by
    maximum marginal likelihood."""
    import torch
    from botorch.models import SingleTaskGP
    from botorch.models.transforms import Normalize, Standardize

    train_X = torch.as_tensor(X, dtype=torch.float64)
    train_Y = torch.as_tensor(Y, dtype=torch.float64).reshape(-1, 1)
    model = SingleTaskGP(
        train_X,
        train_Y,
        input_transform=Normalize(X.shape[1], bounds=torch.as_tensor(bounds, dtype=torch.float64)),
        outcome_transform=Standardize(1),
    )
    return fit_hyperparameters(model, (X - bounds[0]) / (bounds[1] - bounds[0]))


def fit_hyperparameters(model, unit_inputs: np.ndarray):
    """`model` (a `SingleTaskGP` with one or more outputs) with each output's hyperparameters
    fitted by maximum marginal likelihood on its `n x d` inputs in the unit cube:
    `likelihood.maximise_likelihood` (L-BFGS-B capped at FIT_ITERATIONS) from the model's own
    priors, bounds and starting values (BoTorch's defaults), written back into the model;
    single-threaded, so that the result does not depend on the machine's cores."""
    outputs = model.num_outputs
    lengthscale_prior, noise_prior, lower = _priors_and_bounds(model, unit_inputs.shape[1])
    targets = model.train_targets.detach().numpy().reshape(outputs, -1)
    differences = squared_differences(unit_inputs)
    with single_threaded():
        fitted = [
            maximise_likelihood(differences, targets[output], start, lower, lengthscale_prior, noise_prior, FIT_ITERATIONS)
            for output, start in enumerate(_hyperparameters(model, outputs))
        ]
    _set_hyperparameters(model, fitted)
    return model


def _priors_and_bounds(model, dimensions: int) -> tuple[LogNormal, LogNormal, np.ndarray]:
    """The lengthscale and noise priors of `model` and the `d + 2` lower bounds of
    `Hyperparameters.vector` (lengthscales, noise; none for the constant)."""
    kernel, noise = model.covar_module, model.likelihood.noise_covar
    lengthscale_prior = LogNormal(float(kernel.lengthscale_prior.loc), float(kernel.lengthscale_prior.scale))
    noise_prior = LogNormal(float(noise.noise_prior.loc), float(noise.noise_prior.scale))
    lower = np.concatenate(
        [np.full(dimensions, float(kernel.raw_lengthscale_constraint.lower_bound)), [float(noise.raw_noise_constraint.lower_bound), -np.inf]]
    )
    return lengthscale_prior, noise_prior, lower


def _hyperparameters(model, outputs: int) -> list[Hyperparameters]:
    """The current hyperparameters of each of the `outputs` of `model`."""
    import torch

    with torch.no_grad():
        lengthscales = model.covar_module.lengthscale.numpy().reshape(outputs, -1)
        noises = model.likelihood.noise_covar.noise.numpy().reshape(outputs)
        constants = model.mean_module.constant.numpy().reshape(outputs)
    return [Hyperparameters(lengthscales[output], float(noises[output]), float(constants[output])) for output in range(outputs)]


def _set_hyperparameters(model, fitted: list[Hyperparameters]) -> None:
    import torch

    kernel, noise, mean = model.covar_module, model.likelihood.noise_covar, model.mean_module
    with torch.no_grad():
        kernel.lengthscale = torch.as_tensor(np.array([value.lengthscales for value in fitted])).reshape(kernel.lengthscale.shape)
        noise.noise = torch.as_tensor([value.noise for value in fitted], dtype=torch.float64).reshape(noise.noise.shape)
        mean.constant = torch.as_tensor([value.constant for value in fitted], dtype=torch.float64).reshape(mean.constant.shape)


def _float64():
    import torch

    return torch.float64
