"""Composite Bayesian optimisation on the formula's structure (method `stl`).

The robustness of `a & b & c` is a fixed function of its parts' robustness, and each part is a
much smoother function of the skill parameters than the minimum of all of them. So each part
gets its own GP output, and the acquisition is maximised on the composed value by Monte Carlo
through the same semantics (Astudillo & Frazier, "Bayesian Optimization of Composite
Functions", ICML 2019): samples of the `m` parts at a point are composed into samples of the
spec's robustness, and expected improvement is taken over those.

The search runs in a trust region around the best trial (as in TuRBO, Eriksson et al. 2019):
a box whose side grows after successes and shrinks after failures, replayed from the history so
that a resumed run proposes exactly the points an uninterrupted one would.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import numpy as np

from stl_lfd.optim.acquisition import fit_hyperparameters, maximise_acquisition, single_threaded
from stl_lfd.stl import Semantics

MC_SAMPLES = 64
RESTARTS = 4
RAW_SAMPLES = 128
AROUND_ANCHOR = 32  # candidate starts drawn around each anchor trial (see `anchored_starts`)
ANCHOR_SPREAD = 0.1  # their standard deviation, in the unit cube


@dataclass(frozen=True)
class TrustRegion:
    """TuRBO's box, as a side length in the unit cube around the incumbent.

    Attributes:
        initial, minimum, maximum: side at the start, restart threshold, and cap.
        success_tolerance, failure_tolerance: consecutive successes (failures) that double
            (halve) the side.
    """

    initial: float = 0.8
    minimum: float = 0.5**5
    maximum: float = 1.6
    success_tolerance: int = 2
    failure_tolerance: int = 3


def trust_region_length(Y: np.ndarray, initial: int, region: TrustRegion = TrustRegion()) -> float:
    """The side of the trust region after the trials of `Y` (`n` composed values in trial
    order, the first `initial` of them the space-filling design).

    A trial succeeds when it improves the best value so far by more than 1e-3 of the range
    seen; the side doubles after `success_tolerance` successes in a row, halves after
    `failure_tolerance` failures in a row, and starts again at `initial` when it falls below
    `minimum`."""
    length, successes, failures = region.initial, 0, 0
    best = float(np.max(Y[:initial])) if initial > 0 else -np.inf
    scale = float(np.ptp(Y)) if len(Y) > 1 else 1.0
    for value in Y[initial:]:
        if value > best + 1e-3 * max(scale, 1e-12):
            successes, failures = successes + 1, 0
        else:
            successes, failures = 0, failures + 1
        best = max(best, float(value))
        if successes == region.success_tolerance:
            length, successes = min(2 * length, region.maximum), 0
        elif failures == region.failure_tolerance:
            length, failures = length / 2, 0
        if length < region.minimum:
            length = region.initial
    return length


def propose_composite(
    X: np.ndarray,
    parts: np.ndarray,
    Y: np.ndarray,
    bounds: np.ndarray,
    semantics: Semantics,
    initial: int,
    seed: int,
    count: int = 1,
    pending: np.ndarray | None = None,
    groups: int = 1,
    routes: tuple[np.ndarray, tuple[int, ...]] | None = None,
    features: Callable | None = None,
) -> np.ndarray:
    """The next point (or batch of `count` points) of composite BO.

    Args:
        X: `n x d` observed points, in trial order.
        parts: `n x m` robustness of each part of the spec at those points.
        Y: `n` composed robustness (the spec's) at those points.
        bounds: `2 x d`.
        semantics: how the parts compose.
        initial: how many of the first trials were the space-filling design.
        seed: seeds the Monte Carlo samples and the acquisition optimiser's starts.
        count: points to propose at once, for parallel trials. Each point after the first is
            chosen with the earlier ones pending: as if observed at their posterior mean (the
            "Kriging believer", which leaves the mean unchanged and shrinks the variance around
            them), with the same GP hyperparameters.
        pending: `p x d` points being executed (not observed yet), treated the same way.
        groups: the parts are `groups` equal groups side by side (the spec's parts at each of
            several object placements): each group composes by `semantics`, and the result is
            the minimum over the groups.
        routes: `n x r` robustness of formulas that each imply a part, and the index of that
            part for each (`SpecParts.routes`). Each gets its own GP output, and a sample of a
            part is the largest of its own and its routes' samples: a part holds if a route
            does. While the spec is violated the search then spans the whole box, not the
            trust region (the part's own robustness may lead away from where a route is
            close to holding), and the acquisition's optimiser also starts near the trial
            where each part or route was best (`anchored_starts`).
        features: what the GP sees of `b x d` points in the unit cube of `bounds` (a torch
            tensor -> `b x f`; `features.PathFeatures`); None: the points themselves.

    Returns:
        `d` next point, or `count x d` points when `count > 1`.
    """
    import torch

    with single_threaded():
        torch.manual_seed(seed)
        unit = (X - bounds[0]) / (bounds[1] - bounds[0])
        route_values, route_parts = routes if routes is not None else (np.empty((len(X), 0)), ())
        outputs = np.hstack([parts, route_values])
        encode = features if features is not None else (lambda points: points)
        model = fit_multi_output_gp(encode(torch.as_tensor(unit, dtype=torch.float64)).numpy(), outputs)
        posterior = PartsPosterior(model)
        if route_parts and np.max(Y) <= 0:
            box, anchors = _trust_box(np.full(unit.shape[1], 0.5), 1.0), best_trials(outputs, unit)  # the whole unit cube
        else:
            box, anchors = _trust_box(unit[int(np.argmax(Y))], trust_region_length(Y, initial)), None
        executing = [] if pending is None else list((pending - bounds[0]) / (bounds[1] - bounds[0]))
        chosen: list[np.ndarray] = []
        for index in range(count):
            if executing or chosen:
                posterior = PartsPosterior(model).with_pending(encode(torch.as_tensor(np.array(executing + chosen), dtype=torch.float64)))
            acquisition = composed_log_ei(
                model, float(np.max(Y)), float(np.std(Y)) or 1.0, semantics, parts.shape[1], seed + index, posterior, groups, route_parts, features
            )
            starts = None if anchors is None else anchored_starts(acquisition, anchors, box, seed + index)
            chosen.append(maximise_acquisition(acquisition, box, RESTARTS, RAW_SAMPLES, seed + index, starts=starts))
    points = np.clip(bounds[0] + np.array(chosen) * (bounds[1] - bounds[0]), bounds[0], bounds[1])
    return points[0] if count == 1 else points


def composed_log_ei(
    model,
    best: float,
    scale: float,
    semantics: Semantics,
    parts: int,
    seed: int,
    posterior: "PartsPosterior | None" = None,
    groups: int = 1,
    route_parts: tuple[int, ...] = (),
    features: Callable | None = None,
):
    """Log expected improvement of the composed robustness over `best`, by quasi-Monte Carlo.

    The parts' GPs are independent, so at one point their joint posterior is `m` independent
    normals: `MC_SAMPLES` fixed scrambled-Sobol normal draws (`S x m`) are scaled by each
    point's posterior means and standard deviations, composed, and the improvement averaged.
    This is `qLogExpectedImprovement` with a `GenericMCObjective` for q = 1, computed from
    `PartsPosterior` instead of the joint posterior and its Cholesky factor (0.24 s instead of
    1.75 s to maximise on a phi1 history). As in LogEI, the improvement's ReLU is smoothed
    (softplus with temperature `0.01 scale`) and averaged in log space, so that the acquisition
    keeps a gradient far from improvement. The model's outputs after the first `parts` are
    routes: output `parts + k` implies part `route_parts[k]`, whose sample is raised to the
    route's where that is larger. With `features`, the model's inputs are `features(X)`.
    """
    from botorch.acquisition import AcquisitionFunction

    normal = qmc_normals(parts + len(route_parts), seed)  # S x m
    temperature = 0.01 * scale
    posterior = posterior if posterior is not None else PartsPosterior(model)
    encode = features if features is not None else (lambda points: points)

    class ComposedLogEI(AcquisitionFunction):
        def forward(self, X):  # b x 1 x d -> b
            mean, std = posterior(encode(X[..., 0, :]))  # b x m each
            samples = mean.unsqueeze(-2) + std.unsqueeze(-2) * normal  # b x S x (m + r)
            samples = _through_routes(samples, parts, route_parts)  # b x S x m
            return log_soft_improvement(compose(samples, semantics, groups), best, temperature)

    return ComposedLogEI(model)


def qmc_normals(outputs: int, seed: int):
    """`MC_SAMPLES x outputs` fixed standard normal draws (scrambled Sobol, then the inverse CDF)."""
    import torch
    from torch.quasirandom import SobolEngine

    unit = SobolEngine(outputs, scramble=True, seed=seed).draw(MC_SAMPLES, dtype=torch.float64)
    return torch.distributions.Normal(0.0, 1.0).icdf(unit.clamp(1e-6, 1 - 1e-6))


def log_soft_improvement(composed, best: float, temperature: float):
    """`... x S` composed samples -> `...`: the log of their mean improvement over `best`, the
    ReLU smoothed by a softplus of `temperature` as in LogEI, so that it keeps a gradient far
    from improvement."""
    import math

    import torch

    improvement = (composed - best) / temperature
    log_softplus = torch.where(improvement < -30, improvement, torch.nn.functional.softplus(improvement).clamp_min(1e-300).log())
    return torch.logsumexp(log_softplus, dim=-1) - math.log(MC_SAMPLES) + math.log(temperature)


def _through_routes(samples, parts: int, route_parts: tuple[int, ...]):
    """`... x (m + r)` samples of the parts and routes -> `... x m`: each part the largest of
    its own sample and its routes'."""
    import torch

    columns = [samples[..., part] for part in range(parts)]
    for route, part in enumerate(route_parts):
        columns[part] = torch.maximum(columns[part], samples[..., parts + route])
    return torch.stack(columns, dim=-1)


class PartsPosterior:
    """Posterior means and standard deviations of a fitted multi-output `SingleTaskGP` (RBF
    kernel, constant mean, one noise level per output, standardised outputs), computed
    directly from its hyperparameters: `b x d` points -> two `b x m` tensors, in the outputs'
    units. Equal to `model.posterior(X)` (tested) at a fraction of its cost."""

    def __init__(self, model) -> None:
        import torch

        self.pending = None
        with torch.no_grad():
            outputs = model.num_outputs  # a one-output model has no batch dimension: add it
            inputs = model.train_inputs[0].reshape(outputs, -1, model.train_inputs[0].shape[-1])  # m x n x d
            self.lengthscale = model.covar_module.lengthscale.detach().reshape(outputs, 1, -1)  # m x 1 x d
            self.inputs = inputs / self.lengthscale
            kernel = self._kernel(self.inputs, self.inputs)
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

    def with_pending(self, pending) -> "PartsPosterior":
        """This posterior with `p x d` pending points (unit cube) observed at their posterior
        mean: the mean is unchanged, the variance is that of the training and pending inputs."""
        import copy

        import torch

        extended = copy.copy(self)
        with torch.no_grad():
            inputs = torch.cat([self.inputs, (pending.unsqueeze(0) / self.lengthscale)], dim=-2)  # m x (n + p) x d
            kernel = self._kernel(inputs, inputs) + self.noise[..., None] * torch.eye(inputs.shape[-2], dtype=inputs.dtype)
            extended.pending = (inputs, torch.linalg.cholesky(kernel))
        return extended

    @staticmethod
    def _kernel(a, b):
        import torch

        # squared distances expanded (not cdist, whose gradient is NaN at a training point)
        squared = a.square().sum(-1, keepdim=True) - 2 * a @ b.transpose(-1, -2) + b.square().sum(-1).unsqueeze(-2)
        return torch.exp(-0.5 * squared.clamp_min(0.0))

    def __call__(self, X):
        import torch

        scaled = X.unsqueeze(0) / self.lengthscale  # m x b x d
        cross = self._kernel(scaled, self.inputs)  # m x b x n
        mean = self.constant[:, None] + (cross @ self.weights)[..., 0]  # m x b
        inputs, cholesky = self.pending if self.pending is not None else (self.inputs, self.cholesky)
        if self.pending is not None:
            cross = self._kernel(scaled, inputs)  # m x b x (n + p)
        solved = torch.linalg.solve_triangular(cholesky, cross.transpose(-1, -2), upper=False)  # m x n x b
        variance = (1.0 - solved.square().sum(dim=-2)).clamp_min(1e-12)  # m x b
        return (mean * self.y_std[:, None] + self.y_mean[:, None]).T, (variance.sqrt() * self.y_std[:, None]).T


def best_trials(values: np.ndarray, unit: np.ndarray) -> np.ndarray:
    """`k x d`: the points (unit cube) of the trials where some output (a part or a route,
    columns of `n x o` `values`) was at its best, each once, in trial order."""
    return unit[np.unique(np.argmax(values, axis=0))]


def anchored_starts(acquisition, anchors: np.ndarray, box: np.ndarray, seed: int):
    """`k x 1 x d` starting points for the acquisition's optimiser, one near each of the `k x d`
    `anchors`: the best of AROUND_ANCHOR normal draws around it (clipped to `box`).

    Random starts miss what is near a trial in many dimensions: in phi3_strict_final the
    trial where a route was nearly holding (4.6 N against about 110 N elsewhere) had the
    largest expected improvement around it, and none of 128 uniform starts came near it."""
    import torch

    generator = torch.Generator().manual_seed(seed)
    center = torch.as_tensor(anchors, dtype=torch.float64)[:, None, :]  # k x 1 x d
    draws = center + ANCHOR_SPREAD * torch.randn(len(anchors), AROUND_ANCHOR, anchors.shape[1], generator=generator, dtype=torch.float64)
    draws = draws.clamp(torch.as_tensor(box[0]), torch.as_tensor(box[1]))  # k x A x d
    with torch.no_grad():
        values = acquisition(draws.reshape(-1, 1, anchors.shape[1])).reshape(len(anchors), AROUND_ANCHOR)
    return draws[torch.arange(len(anchors)), values.argmax(dim=-1)][:, None, :]


def _trust_box(center: np.ndarray, length: float) -> np.ndarray:
    """`2 x d` box of side `length` around `center` in the unit cube, clipped to it."""
    return np.vstack([np.clip(center - length / 2, 0.0, 1.0), np.clip(center + length / 2, 0.0, 1.0)])


def fit_multi_output_gp(unit_X, parts: np.ndarray):
    """A `SingleTaskGP` with one independent output per part (`n x d` inputs in the unit cube,
    `n x m` outputs standardised per part), fitted by maximum marginal likelihood."""
    import torch
    from botorch.models import SingleTaskGP
    from botorch.models.transforms import Standardize

    train_X = torch.as_tensor(unit_X, dtype=torch.float64)
    train_Y = torch.as_tensor(parts, dtype=torch.float64)
    return fit_hyperparameters(SingleTaskGP(train_X, train_Y, outcome_transform=Standardize(train_Y.shape[-1])), unit_X)


def compose(values, semantics: Semantics, groups: int = 1):
    """The spec's robustness from its parts' values in torch: `... x m` -> `...`.

    The same formulas as `stl_lfd.stl` (minimum for classic, the new robustness's n-ary
    conjunction), written so that gradients stay finite in both branches. With `groups`, the
    `m` values are that many groups of parts side by side, and the result is the minimum of
    the groups' compositions."""
    import torch

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
