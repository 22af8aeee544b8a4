"""The spec's robustness composed from its parts' samples, in torch: the composition itself
(`compose`, the same formulas as `stl_lfd.stl`), routes, quasi-Monte Carlo draws, and the log
expected improvement of the composed value (`ComposedLogEI`), shared by methods `stl` and `plan`.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np
import torch
from botorch.acquisition import AcquisitionFunction
from torch.quasirandom import SobolEngine

from stl_lfd.optim.methods.posterior import PartsPosterior
from stl_lfd.stl import Semantics

MC_SAMPLES = 64  # quasi-Monte Carlo draws of the parts per point


class ComposedLogEI(AcquisitionFunction):
    """Log expected improvement of the composed robustness over `best`, by quasi-Monte Carlo.

    The parts' GPs are independent, so at one point their joint posterior is `m` independent
    normals: fixed scrambled-Sobol normal draws (`S x m`, `qmc_normals`) are scaled by each
    point's posterior means and standard deviations, composed, and the improvement averaged.
    This is `qLogExpectedImprovement` with a `GenericMCObjective` for q = 1, computed from
    `PartsPosterior` instead of the joint posterior and its Cholesky factor (several times
    cheaper). As in LogEI, the improvement's ReLU is smoothed
    (softplus with temperature `0.01 scale`) and averaged in log space, so that the acquisition
    keeps a gradient far from improvement. The model's outputs after the first `parts` are
    routes: output `parts + k` implies part `route_parts[k]`, whose sample is raised to the
    route's where that is larger. With `features`, the model's inputs are `features(X)`; with
    `scales` (`m + r`, `balance.output_scales`), each output's samples are divided by its scale
    before they are composed (`best` then is on that scale too).
    """

    def __init__(
        self,
        model,
        posterior: PartsPosterior,
        best: float,
        scale: float,
        semantics: Semantics,
        parts: int,
        seed: int,
        groups: int = 1,
        route_parts: tuple[int, ...] = (),
        features: Callable | None = None,
        scales: np.ndarray | None = None,
    ) -> None:
        super().__init__(model)
        self.posterior, self.best, self.temperature = posterior, best, 0.01 * scale
        self.semantics, self.parts, self.groups, self.route_parts = semantics, parts, groups, route_parts
        self.normal = qmc_normals(parts + len(route_parts), seed)  # S x (m + r)
        self.encode = features if features is not None else (lambda points: points)
        self.scales = None if scales is None else torch.as_tensor(scales, dtype=torch.float64)

    def forward(self, X: torch.Tensor) -> torch.Tensor:  # b x 1 x d -> b
        mean, std = self.posterior(self.encode(X[..., 0, :]))  # b x (m + r) each
        samples = mean.unsqueeze(-2) + std.unsqueeze(-2) * self.normal  # b x S x (m + r)
        if self.scales is not None:
            samples = samples / self.scales
        samples = through_routes(samples, self.parts, self.route_parts)  # b x S x m
        return log_soft_improvement(compose(samples, self.semantics, self.groups), self.best, self.temperature)


def qmc_normals(outputs: int, seed: int, samples: int = MC_SAMPLES) -> torch.Tensor:
    """`samples x outputs` fixed standard normal draws (scrambled Sobol, then the inverse CDF)."""
    unit = SobolEngine(outputs, scramble=True, seed=seed).draw(samples, dtype=torch.float64)
    return torch.distributions.Normal(0.0, 1.0).icdf(unit.clamp(1e-6, 1 - 1e-6))


def log_soft_improvement(composed: torch.Tensor, best: float, temperature: float) -> torch.Tensor:
    """`... x S` composed samples -> `...`: the log of their mean improvement over `best`, the
    ReLU smoothed by a softplus of `temperature` as in LogEI, so that it keeps a gradient far
    from improvement."""
    improvement = (composed - best) / temperature
    log_softplus = torch.where(improvement < -30, improvement, torch.nn.functional.softplus(improvement).clamp_min(1e-300).log())
    return torch.logsumexp(log_softplus, dim=-1) - math.log(composed.shape[-1]) + math.log(temperature)


def through_routes(samples: torch.Tensor, parts: int, route_parts: tuple[int, ...]) -> torch.Tensor:
    """`... x (m + r)` samples of the parts and routes -> `... x m`: each part the largest of
    its own sample and its routes'."""
    columns = [samples[..., part] for part in range(parts)]
    for route, part in enumerate(route_parts):
        columns[part] = torch.maximum(columns[part], samples[..., parts + route])
    return torch.stack(columns, dim=-1)


def compose(values: torch.Tensor, semantics: Semantics, groups: int = 1) -> torch.Tensor:
    """The spec's robustness from its parts' values: `... x m` -> `...`.

    The same formulas as `stl_lfd.stl.kernels.conjunction` (minimum for classic,
    `new_conjunction` for the new robustness), mirrored in torch so that gradients stay finite in
    both branches; tests/optim/test_composite.py holds the two equal. With `groups`, the
    `m` values are that many groups of parts side by side, and the result is the minimum of
    the groups' compositions."""
    if groups > 1:
        grouped = values.reshape(*values.shape[:-1], groups, values.shape[-1] // groups)
        return compose(grouped, semantics).min(dim=-1).values

    minimum = values.min(dim=-1, keepdim=True).values
    if semantics.name == "classic":
        return minimum[..., 0]
    nu = semantics.nu
    safe_minimum = torch.where(minimum != 0, minimum, torch.ones_like(minimum))
    relative = (values - safe_minimum) / safe_minimum
    negative_relative = torch.where(minimum < 0, relative, torch.zeros_like(relative))  # <= 0 there
    positive_relative = torch.where(minimum > 0, relative, torch.zeros_like(relative))  # >= 0 there
    negative = safe_minimum[..., 0] * (torch.softmax(nu * negative_relative, dim=-1) * torch.exp(negative_relative)).sum(dim=-1)
    positive = (values * torch.softmax(-nu * positive_relative, dim=-1)).sum(dim=-1)
    minimum = minimum[..., 0]
    return torch.where(minimum > 0, positive, torch.where(minimum < 0, negative, torch.zeros_like(minimum)))
