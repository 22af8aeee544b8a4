"""The parts' GP fit (method `stl`): gpytorch's marginal likelihood computed in numpy."""

import numpy as np
import pytest
import torch

from stl_lfd.optim.methods.gp import fit_multi_output_gp
from stl_lfd.optim.methods.likelihood import Hyperparameters, LogNormal, negative_log_likelihood, squared_differences


def _model_and_data(outputs, seed=0, count=15, dimensions=4):
    from botorch.models import SingleTaskGP
    from botorch.models.transforms import Standardize

    rng = np.random.default_rng(seed)
    inputs = rng.random((count, dimensions))
    parts = np.stack([np.sin(inputs @ rng.normal(size=dimensions) * 3) + 0.1 * rng.normal(size=count) for _ in range(outputs)], axis=-1)
    model = SingleTaskGP(torch.as_tensor(inputs), torch.as_tensor(parts), outcome_transform=Standardize(outputs))
    return model, inputs, parts


def _gpytorch_losses(model):
    """Minus gpytorch's ExactMarginalLogLikelihood of each output, with its autograd gradient."""
    from gpytorch.mlls import ExactMarginalLogLikelihood

    model.train()
    mll = ExactMarginalLogLikelihood(model.likelihood, model)
    losses = -mll(model(*model.train_inputs), model.train_targets).reshape(-1)
    return losses


def _priors(model):
    kernel, noise = model.covar_module, model.likelihood.noise_covar
    return LogNormal(float(kernel.lengthscale_prior.loc), float(kernel.lengthscale_prior.scale)), LogNormal(
        float(noise.noise_prior.loc), float(noise.noise_prior.scale)
    )


@pytest.mark.parametrize("outputs", [1, 3])
def test_the_likelihood_and_its_gradient_are_gpytorchs(outputs):
    model, inputs, _ = _model_and_data(outputs)
    rng = np.random.default_rng(1)
    with torch.no_grad():
        model.covar_module.lengthscale = torch.as_tensor(rng.uniform(0.1, 2.0, model.covar_module.lengthscale.shape))
        model.likelihood.noise_covar.noise = torch.as_tensor(rng.uniform(1e-3, 0.5, model.likelihood.noise_covar.noise.shape))
        model.mean_module.constant = torch.as_tensor(rng.normal(size=model.mean_module.constant.shape))
    losses = _gpytorch_losses(model)
    targets = model.train_targets.detach().numpy().reshape(outputs, -1)
    lengthscales = model.covar_module.lengthscale.detach().numpy().reshape(outputs, -1)
    noises = model.likelihood.noise_covar.noise.detach().numpy().reshape(outputs)
    constants = model.mean_module.constant.detach().numpy().reshape(outputs)
    lengthscale_prior, noise_prior = _priors(model)
    for output in range(outputs):
        vector = Hyperparameters(lengthscales[output], float(noises[output]), float(constants[output])).vector()
        loss, gradient = negative_log_likelihood(vector, squared_differences(inputs), targets[output], lengthscale_prior, noise_prior)
        parameters = [model.covar_module.raw_lengthscale, model.likelihood.noise_covar.raw_noise, model.mean_module.raw_constant]
        expected = torch.autograd.grad(losses[output], parameters, retain_graph=True)  # raw values are the values (no transform)
        expected_gradient = np.concatenate(
            [expected[0].numpy().reshape(outputs, -1)[output], expected[1].numpy().reshape(outputs)[[output]], expected[2].numpy().reshape(outputs)[[output]]]
        )
        np.testing.assert_allclose(loss, float(losses[output].detach()), rtol=1e-8)
        np.testing.assert_allclose(gradient, expected_gradient, rtol=1e-6, atol=1e-8)  # gpytorch centres the inputs first


def test_the_fit_raises_every_outputs_likelihood_and_keeps_the_bounds():
    model, inputs, parts = _model_and_data(3, seed=2, count=25, dimensions=6)
    before = _gpytorch_losses(model).detach().numpy()
    fitted = fit_multi_output_gp(inputs, parts)
    after = _gpytorch_losses(fitted).detach().numpy()
    assert np.all(after < before - 0.05)
    assert torch.all(fitted.covar_module.lengthscale >= 0.025) and torch.all(fitted.likelihood.noise_covar.noise >= 1e-4)


def test_a_matrix_that_is_not_positive_definite_is_an_infinite_loss_not_an_error():
    inputs = np.zeros((3, 2))  # three equal points: K = 1 + noise everywhere, singular without noise
    lengthscale_prior, noise_prior = LogNormal(1.0, 1.0), LogNormal(-4.0, 1.0)
    loss, gradient = negative_log_likelihood(np.array([1.0, 1.0, -0.5, 0.0]), squared_differences(inputs), np.zeros(3), lengthscale_prior, noise_prior)
    assert loss == np.inf and np.all(gradient == 0)


def test_pis_gp_is_fitted_the_same_way_on_inputs_normalised_to_the_bounds():
    from stl_lfd.optim.methods.gp import fit_gp

    rng = np.random.default_rng(5)
    bounds = np.array([[-2.0, 0.0, 10.0], [2.0, 0.5, 30.0]])
    X = bounds[0] + rng.random((20, 3)) * (bounds[1] - bounds[0])
    Y = np.sin(X[:, 0]) + X[:, 1] - 0.01 * X[:, 2]
    model = fit_gp(X, Y, bounds)
    fitted = _gpytorch_losses(model).detach().numpy()
    with torch.no_grad():  # back to BoTorch's starting values: the fit must have improved on them
        model.covar_module.lengthscale = torch.full_like(
            model.covar_module.lengthscale, float(np.exp(model.covar_module.lengthscale_prior.loc - model.covar_module.lengthscale_prior.scale**2))
        )
        model.likelihood.noise_covar.noise = torch.full_like(model.likelihood.noise_covar.noise, float(np.exp(-5.0)))
        model.mean_module.constant = torch.zeros_like(model.mean_module.constant)
    assert np.all(fitted < _gpytorch_losses(model).detach().numpy() - 0.05)


def test_the_fit_does_not_depend_on_the_number_of_blas_threads():
    """OpenBLAS's triangular solve rounds differently on one thread and on two (on these
    inputs, by 1e-17), and L-BFGS-B magnifies that: a seed must give the same trials on a
    machine with more cores."""
    import scipy.linalg  # noqa: F401 (loads scipy's own OpenBLAS, so that the limits below reach it)
    from threadpoolctl import threadpool_limits

    rng = np.random.default_rng(4)
    inputs = rng.random((13, 12))
    parts = np.stack([np.sin(inputs @ rng.normal(size=12) * 2), np.cos(inputs @ rng.normal(size=12))], axis=-1)
    fitted = []
    for threads in (1, 2):
        with threadpool_limits(limits=threads, user_api="blas"):
            model = fit_multi_output_gp(inputs, parts)
        fitted.append(np.concatenate([model.covar_module.lengthscale.detach().numpy().ravel(), model.likelihood.noise.detach().numpy().ravel()]))
    assert np.array_equal(fitted[0], fitted[1])
