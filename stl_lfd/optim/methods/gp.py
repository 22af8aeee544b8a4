"""Gaussian processes for the search methods: BoTorch's `SingleTaskGP` with hyperparameters
fitted by our numpy likelihood (`likelihood.py`), and the multi-start maximisation of an
acquisition function.

BoTorch and torch are imported inside the functions: they cost about 2 s to import, which
commands that never optimise should not pay.
"""

from __future__ import annotations

import warnings
from contextlib import contextmanager
from typing import Iterator

import numpy as np

from stl_lfd.optim.methods.likelihood import Hyperparameters, LogNormal, maximise_likelihood, squared_differences

# L-BFGS-B iterations of the GP hyperparameter fit (per output): 100 reach a marginal log
# likelihood within 0.001 of the converged one at n = 30, d = 21 (measured with gpytorch's fit
# of the same likelihood).
FIT_ITERATIONS = 100


@contextmanager
def single_threaded() -> Iterator[None]:
    """Torch and BLAS on one thread for the block, restored afterwards: the matrices are tiny,
    and the same seed must give the same trials whatever the number of cores."""
    # One thread is as fast as two for n <= a few hundred, and OpenMP threads spinning against
    # the simulator or a parallel run made proposals 30x slower on 2 cores. BLAS too: OpenBLAS's
    # triangular solve rounds differently with more threads, the GP fit's L-BFGS-B magnifies
    # that, and the same seed gave other trials on a machine with another core count.
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


def fit_gp(X: np.ndarray, Y: np.ndarray, bounds: np.ndarray):
    """A one-output `SingleTaskGP` on `n x d` points `X` and `n` values `Y` (inputs normalised
    to the `2 x d` bounds, outputs standardised), fitted by maximum marginal likelihood."""
    import torch
    from botorch.models import SingleTaskGP
    from botorch.models.transforms import Normalize, Standardize

    from stl_lfd.optim.methods.base import to_unit

    train_X = torch.as_tensor(X, dtype=torch.float64)
    train_Y = torch.as_tensor(Y, dtype=torch.float64).reshape(-1, 1)
    model = SingleTaskGP(
        train_X,
        train_Y,
        input_transform=Normalize(X.shape[1], bounds=torch.as_tensor(bounds, dtype=torch.float64)),
        outcome_transform=Standardize(1),
    )
    return fit_hyperparameters(model, to_unit(X, bounds))


def fit_multi_output_gp(unit_X: np.ndarray, outputs: np.ndarray):
    """A `SingleTaskGP` with one independent output per column of `n x m` `outputs` (each
    standardised) on `n x d` inputs in the unit cube, fitted by maximum marginal likelihood."""
    import torch
    from botorch.exceptions.warnings import InputDataWarning
    from botorch.models import SingleTaskGP
    from botorch.models.transforms import Standardize

    train_X = torch.as_tensor(unit_X, dtype=torch.float64)
    train_Y = torch.as_tensor(outputs, dtype=torch.float64)
    with warnings.catch_warnings():
        # a part of the spec whose value no trial has changed yet cannot be standardised (std 0); its GP is flat, as intended
        warnings.simplefilter("ignore", InputDataWarning)
        model = SingleTaskGP(train_X, train_Y, outcome_transform=Standardize(train_Y.shape[-1]))
    return fit_hyperparameters(model, unit_X)


def fit_hyperparameters(model, unit_inputs: np.ndarray, iterations: int = FIT_ITERATIONS):
    """`model` (a `SingleTaskGP` with one or more outputs) with each output's hyperparameters
    fitted by maximum marginal likelihood on its `n x d` inputs in the unit cube:
    `likelihood.maximise_likelihood` (L-BFGS-B capped at `iterations`) from the model's own
    priors, bounds and starting values (BoTorch's defaults), written back into the model;
    single-threaded, so that the result does not depend on the machine's cores."""
    outputs = model.num_outputs
    lengthscale_prior, noise_prior, lower = _priors_and_bounds(model, unit_inputs.shape[1])
    targets = model.train_targets.detach().numpy().reshape(outputs, -1)
    differences = squared_differences(unit_inputs)
    with single_threaded():
        fitted = [
            maximise_likelihood(differences, targets[output], start, lower, lengthscale_prior, noise_prior, iterations)
            for output, start in enumerate(_hyperparameters(model, outputs))
        ]
    _set_hyperparameters(model, fitted)
    return model


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


# --- Helper functions: the model's hyperparameters as numpy values ---


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
