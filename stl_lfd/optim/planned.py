"""Composite BO with the plan as the prior (method `plan`).

Before a trial executes, the tool already knows what it will ask the robot to do: the
reference retrieved from the adapted skill. Scored as it stands (the kinematic backend, about
40-90 ms), this plan gives the robustness of every part of the spec without a robot trial. The
execution differs from the plan by what the plan cannot know: tracking errors, and contact
(the plan records no force). So each part's GP models the difference between execution and
plan, starting from none, and a part's sample at a point is the plan's value plus a sample of
the difference; the samples are composed through the spec's semantics as in method `stl`
(`composite.py`), and expected improvement is taken over them.

The plan is not differentiable, so the acquisition is maximised over a finite set of
candidates: a scrambled Sobol pool of the box (its plans computed once per run), then rounds of
normal perturbations around the best candidates so far, each round closer. Everything depends
only on the history, the seed and the trial number (the plans are a pure function of the
point), so a resumed run proposes the points an uninterrupted one did.

Where the plan predicts the execution (positions in free space), the first trial is already
the best point the plan search found; where it does not (the force of an insertion), the
difference's GP learns the part from the trials.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np

from stl_lfd.optim.acquisition import single_threaded
from stl_lfd.optim.composite import PartsPosterior, _through_routes, compose, fit_multi_output_gp, log_soft_improvement, qmc_normals
from stl_lfd.stl import Semantics

POOL = 128  # Sobol candidates whose plans are computed once per run
# Refinement rounds: the standard deviation (unit cube) of each round's draws, how many of the
# best candidates are perturbed (after the first trial, the best trial too), and how many
# draws around each. The first trial, chosen by the plan alone, gets a longer search (once per
# run); later ones stay cheap, 40 plans, as the trials' history carries the search on.
FIRST_ROUNDS = ((0.1, 0.04, 0.015, 0.006), 4, 8)
ROUNDS = ((0.08, 0.02), 3, 5)
PENDING_SPREAD = 0.05  # no point of a batch this close (unit cube, any coordinate) to another


class Plan:
    """The plan's robustness of each output (the spec's parts, then its routes) at points of the
    unit cube of `bounds`: `b x d` -> `b x o`, a row of NaN where the reference could not be
    built or scored. Memoised: the same point is planned once.

    Args:
        score: x (`d`, in parameter units) -> `o` values (raises for a point without a plan).
        bounds: `2 x d` parameter bounds.
    """

    def __init__(self, score: Callable[[np.ndarray], np.ndarray], bounds: np.ndarray) -> None:
        self.score, self.bounds = score, bounds
        self.memo: dict[bytes, np.ndarray] = {}

    def __call__(self, unit: np.ndarray) -> np.ndarray:
        return np.array([self._one(point) for point in np.atleast_2d(unit)])

    def _one(self, point: np.ndarray) -> np.ndarray:
        key = point.tobytes()
        if key not in self.memo:
            x = self.bounds[0] + point * (self.bounds[1] - self.bounds[0])
            try:
                values = np.asarray(self.score(x), dtype=float)
            except Exception:  # no reference for this point: never a candidate
                values = None
            self.memo[key] = values
        values = self.memo[key]
        return values if values is not None else np.full(self._outputs(), np.nan)

    def _outputs(self) -> int:
        known = next((values for values in self.memo.values() if values is not None), None)
        return 1 if known is None else len(known)


def propose_planned(
    X: np.ndarray,
    outputs: np.ndarray,
    Y: np.ndarray,
    bounds: np.ndarray,
    semantics: Semantics,
    parts: int,
    plan: Plan,
    seed: int,
    trial_seed: int,
    groups: int = 1,
    route_parts: tuple[int, ...] = (),
    features: Callable | None = None,
    design: bool = False,
    tried: np.ndarray | None = None,
    pending: np.ndarray | None = None,
) -> np.ndarray:
    """The next point (`d`) of method `plan`.

    The first trial is the best point of the plan search. The other trials of the initial
    design (`design`) spread over the points the plan says satisfy the spec (`spread_point`),
    so that the parts the plan cannot see are sampled across the box, as Sobol trials would;
    after them, the acquisition on plan + difference chooses.

    Args:
        X: `n x d` observed points (n may be 0).
        outputs: `n x o` robustness of the spec's parts (then routes) at those points.
        Y: `n` composed robustness at those points.
        bounds: `2 x d`.
        semantics: how the parts compose; `groups`: equal groups of parts, the minimum over
            them (several placements); `route_parts`: the part each route implies.
        parts: `m`, how many of the `o` outputs are parts.
        plan: the plan of each output at unit-cube points.
        seed: the run's seed (the pool); `trial_seed`: this proposal's (draws and samples).
        features: what the GP sees of `b x d` unit-cube points (`features.PathFeatures`).
        design: whether this trial is one of the initial design's.
        tried: `k x d` points of every trial so far, failed ones too (default: `X`); none is
            proposed again.
        pending: `p x d` points executing or chosen for the same batch (among `tried`): no
            point within PENDING_SPREAD of them is proposed, so that a batch spreads out.
    """
    with single_threaded():
        unit = (X - bounds[0]) / (bounds[1] - bounds[0])
        tried = unit if tried is None else (tried - bounds[0]) / (bounds[1] - bounds[0])
        if design and len(tried):
            chosen = spread_point(sobol_pool(bounds.shape[1], seed), plan, tried, semantics, parts, groups, route_parts)
            return bounds[0] + chosen * (bounds[1] - bounds[0])
        difference = _difference_posterior(unit, outputs - plan(unit) if len(X) else outputs, features)
        best = float(np.max(Y)) if len(Y) else -np.inf
        scale = float(np.std(Y)) if len(Y) > 1 and np.std(Y) > 0 else 1.0
        score = _scorer(difference, plan, best, scale, semantics, parts, groups, route_parts, trial_seed, features)
        candidates = sobol_pool(bounds.shape[1], seed)
        values = score(candidates)
        generator = np.random.default_rng([seed, trial_seed])
        spreads, centre_count, draw_count = ROUNDS if len(X) else FIRST_ROUNDS
        best_trial = unit[np.argmax(Y, keepdims=True)] if len(Y) else unit[:0]  # its neighbourhood may rank lower
        for spread in spreads:
            centres = np.vstack([best_trial, candidates[np.argsort(-values, kind="stable")[:centre_count]]])
            draws = np.clip(centres[:, None, :] + spread * generator.standard_normal((len(centres), draw_count, bounds.shape[1])), 0.0, 1.0)
            draws = draws.reshape(-1, bounds.shape[1])
            candidates, values = np.vstack([candidates, draws]), np.concatenate([values, score(draws)])
        values = np.where(_within(candidates, tried, 1e-9), -np.inf, values)  # a point already executed would teach nothing new
        if pending is not None and len(pending):
            values = np.where(_within(candidates, (pending - bounds[0]) / (bounds[1] - bounds[0]), PENDING_SPREAD), -np.inf, values)
    chosen = candidates[int(np.argmax(values))]
    return np.clip(bounds[0] + chosen * (bounds[1] - bounds[0]), bounds[0], bounds[1])


def spread_point(pool: np.ndarray, plan: Plan, tried: np.ndarray, semantics: Semantics, parts: int, groups: int, route_parts) -> np.ndarray:
    """The point of `pool` (`P x d`, unit cube) farthest from the `n x d` `tried` points among
    the untried ones whose plan satisfies the spec (or, when none is left, among the best
    quarter by plan)."""
    import torch

    planned = plan(pool)
    values = compose(_through_routes(torch.as_tensor(np.nan_to_num(planned, nan=-1e9)), parts, route_parts), semantics, groups).numpy()
    values = np.where(np.isfinite(planned).all(axis=1), values, -np.inf)
    distance = np.min(np.linalg.norm(pool[:, None, :] - tried[None, :, :], axis=-1), axis=1)
    untried = distance > 1e-9
    eligible = untried & (values > 0)
    if not eligible.any():
        eligible = untried & (values >= np.quantile(values[untried], 0.75))
    return pool[int(np.argmax(np.where(eligible, distance, -np.inf)))]


def _within(points: np.ndarray, others: np.ndarray, distance: float) -> np.ndarray:
    """`b` flags: whether each of `b x d` `points` is within `distance` (largest coordinate
    difference) of one of `k x d` `others`."""
    if not len(others):
        return np.zeros(len(points), dtype=bool)
    return np.min(np.abs(points[:, None, :] - others[None, :, :]).max(axis=-1), axis=1) < distance


def sobol_pool(dimension: int, seed: int) -> np.ndarray:
    """The run's `POOL x d` candidates: scrambled Sobol points of the unit cube."""
    import torch
    from torch.quasirandom import SobolEngine

    return SobolEngine(dimension, scramble=True, seed=seed).draw(POOL, dtype=torch.float64).numpy()


def _difference_posterior(unit: np.ndarray, difference: np.ndarray, features: Callable | None):
    """Posterior means and standard deviations (`b x o` each) of the execution's difference
    from the plan at `b x d` unit-cube points, as a function of numpy points.

    Before any trial the difference is 0. An output whose difference has been the same at
    every trial (or seen at one trial only) is that value give or take as much, anywhere: 0
    exactly while the execution is the plan (the kinematic backend). The others get a GP each.
    """
    import torch

    encode = features if features is not None else (lambda points: points)
    known = np.isfinite(difference).all(axis=1)
    unit, difference = unit[known], difference[known]
    outputs = difference.shape[1]
    mean = difference.mean(axis=0) if len(difference) else np.zeros(outputs)
    std = np.abs(mean)
    varying = np.ptp(difference, axis=0) > 0 if len(difference) >= 2 else np.zeros(outputs, dtype=bool)
    posterior = None
    if varying.any():
        inputs = encode(torch.as_tensor(unit, dtype=torch.float64)).numpy()
        posterior = PartsPosterior(fit_multi_output_gp(inputs, difference[:, varying]))

    def predict(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        means, stds = np.tile(mean, (len(points), 1)), np.tile(std, (len(points), 1))
        if posterior is not None:
            with torch.no_grad():
                fitted_mean, fitted_std = posterior(encode(torch.as_tensor(points, dtype=torch.float64)))
            means[:, varying], stds[:, varying] = fitted_mean.numpy(), fitted_std.numpy()
        return means, stds

    return predict


def _scorer(difference, plan: Plan, best: float, scale: float, semantics: Semantics, parts: int, groups: int, route_parts, seed: int, features):
    """`b x d` unit points -> `b` acquisition values: the log expected improvement over `best`
    of the composed samples of plan + difference (as `composite.composed_log_ei`), or the
    composed mean before any trial; -inf where there is no plan."""
    import torch

    normal = qmc_normals(parts + len(route_parts), seed)  # S x o

    def score(points: np.ndarray) -> np.ndarray:
        planned = plan(points)  # b x o
        mean, std = difference(points)
        centre = torch.as_tensor(planned + mean, dtype=torch.float64)
        spread = torch.as_tensor(std, dtype=torch.float64)
        samples = _through_routes(centre.unsqueeze(-2) + spread.unsqueeze(-2) * normal, parts, route_parts)
        composed = compose(torch.nan_to_num(samples, nan=-1e9), semantics, groups)  # b x S
        values = composed.mean(dim=-1) if not math.isfinite(best) else log_soft_improvement(composed, best, 0.01 * scale)
        return np.where(np.isfinite(planned).all(axis=1), values.numpy(), -np.inf)

    return score
