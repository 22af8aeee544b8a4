"""`PartsPosterior`: the posterior of a fitted multi-output GP, computed from its hyperparameters."""

from __future__ import annotations

import copy

import torch


class PartsPosterior:
    """Posterior means and standard deviations of a fitted multi-output `SingleTaskGP` (RBF
    kernel, constant mean, one noise level per output, standardised outputs), computed
    directly from its hyperparameters: `b x d` points -> two `b x m` tensors, in the outputs'
    units. Equal to `model.posterior(X)` (tested) at a fraction of its cost."""

    def __init__(self, model) -> None:
        self.pending = None
        with torch.no_grad():
            outputs = model.num_outputs  # a one-output model has no batch dimension: add it
            inputs = model.train_inputs[0].reshape(outputs, -1, model.train_inputs[0].shape[-1])  # m x n x d
            self.lengthscale = model.covar_module.lengthscale.detach().reshape(outputs, 1, -1)  # m x 1 x d
            self.inputs = inputs / self.lengthscale
            kernel = _kernel(self.inputs, self.inputs)
            noise = model.likelihood.noise.detach().reshape(outputs, 1)
            kernel = kernel + noise[..., None] * torch.eye(inputs.shape[-2], dtype=inputs.dtype)
            self.cholesky = torch.linalg.cholesky(kernel)  # m x n x n
            constant = model.mean_module.constant.detach().reshape(outputs)
            residual = (model.train_targets.reshape(outputs, -1) - constant[:, None]).unsqueeze(-1)  # m x n x 1
            self.weights = torch.cholesky_solve(residual, self.cholesky)  # m x n x 1
            self.constant = constant
            self.y_mean = model.outcome_transform.means.detach()[0]  # m
            self.y_std = model.outcome_transform.stdvs.detach()[0]  # m
            self.noise = noise

    def with_pending(self, pending: torch.Tensor) -> "PartsPosterior":
        """This posterior with `p x d` pending points (unit cube) observed at their posterior
        mean: the mean is unchanged, the variance is that of the training and pending inputs."""
        extended = copy.copy(self)
        with torch.no_grad():
            inputs = torch.cat([self.inputs, (pending.unsqueeze(0) / self.lengthscale)], dim=-2)  # m x (n + p) x d
            kernel = _kernel(inputs, inputs) + self.noise[..., None] * torch.eye(inputs.shape[-2], dtype=inputs.dtype)
            extended.pending = (inputs, torch.linalg.cholesky(kernel))
        return extended

    def __call__(self, X: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        scaled = X.unsqueeze(0) / self.lengthscale  # m x b x d
        cross = _kernel(scaled, self.inputs)  # m x b x n
        mean = self.constant[:, None] + (cross @ self.weights)[..., 0]  # m x b
        inputs, cholesky = self.pending if self.pending is not None else (self.inputs, self.cholesky)
        if self.pending is not None:
            cross = _kernel(scaled, inputs)  # m x b x (n + p)
        solved = torch.linalg.solve_triangular(cholesky, cross.transpose(-1, -2), upper=False)  # m x n x b
        variance = (1.0 - solved.square().sum(dim=-2)).clamp_min(1e-12)  # m x b
        return (mean * self.y_std[:, None] + self.y_mean[:, None]).T, (variance.sqrt() * self.y_std[:, None]).T


def _kernel(a: torch.Tensor, b: torch.Tensor) -> torch.Tensor:
    """The RBF kernel of lengthscale-scaled points `... x n x d` and `... x k x d` -> `... x n x k`."""
    # squared distances expanded (not cdist, whose gradient is NaN at a training point)
    squared = a.square().sum(-1, keepdim=True) - 2 * a @ b.transpose(-1, -2) + b.square().sum(-1).unsqueeze(-2)
    return torch.exp(-0.5 * squared.clamp_min(0.0))
