"""Method `plan`'s model of a point: its plan (memoised), the execution's difference from the
plan (`difference_posterior`), and the acquisition over both (`Scorer`)."""

from __future__ import annotations

import math
from typing import Callable

import numpy as np
import torch

from stl_lfd.optim.methods.base import Composition, from_unit
from stl_lfd.optim.methods.composition import compose, log_soft_improvement, qmc_normals, through_routes
from stl_lfd.optim.methods.gp import fit_multi_output_gp
from stl_lfd.optim.methods.posterior import PartsPosterior


class Plan:
    """The plan's robustness of each output (the spec's parts, then its routes) at points of the
    unit cube of `bounds`: `b x d` -> `b x o`, a row of NaN where the reference could not be
    built or scored. Memoised: the same point is planned once. The points not planned yet are
    planned in one batch; when the batch fails, each point on its own, so that only the points
    without a plan get NaN.

    Args:
        score: `b x d` points (parameter units) -> `b x o` values (raises when a point has no
            plan).
        bounds: `2 x d` parameter bounds.
    """

    def __init__(self, score: Callable[[np.ndarray], np.ndarray], bounds: np.ndarray) -> None:
        self.score, self.bounds = score, bounds
        self.memo: dict[bytes, np.ndarray | None] = {}

    def __call__(self, unit: np.ndarray) -> np.ndarray:
        unit = np.atleast_2d(unit)
        keys = [point.tobytes() for point in unit]
        new = {key: point for key, point in zip(keys, unit) if key not in self.memo}
        if new:
            self._plan(np.array(list(new.values())))
        missing = np.full(self._outputs(), np.nan)
        return np.array([missing if self.memo[key] is None else self.memo[key] for key in keys])

    def _plan(self, unit: np.ndarray) -> None:
        """Plan `b x d` unit points into the memo (None for a point without a plan)."""
        try:
            values = np.asarray(self.score(from_unit(unit, self.bounds)), dtype=float)
        except Exception:  # no reference for some point: find which, alone
            if len(unit) > 1:
                for point in unit:
                    self._plan(point[None])
                return
            values = None
        for index, point in enumerate(unit):
            self.memo[point.tobytes()] = None if values is None else values[index]

    def _outputs(self) -> int:
        known = next((values for values in self.memo.values() if values is not None), None)
        return 1 if known is None else len(known)


Posterior = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]  # b x d unit points -> b x o means, b x o stds


def difference_posterior(unit: np.ndarray, difference: np.ndarray, features: Callable | None) -> Posterior:
    """Posterior means and standard deviations (`b x o` each) of the execution's difference
    from the plan (`n x o`, observed at `n x d` unit-cube points), as a function of numpy points.

    Before any trial the difference is 0. An output whose difference has been the same at
    every trial (or seen at one trial only) is that value give or take as much, anywhere: 0
    exactly while the execution is the plan (the kinematic backend). The others get a GP each.
    """
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


class Scorer:
    """`b x d` unit points -> `b` acquisition values: the log expected improvement over `best`
    of the composed samples of plan + difference (as `composition.ComposedLogEI`), or the
    composed mean before any trial (`best` = -inf); -inf where there is no plan. With `scales`
    (`o`), each output is divided by its scale before they are composed (`balance.py`)."""

    def __init__(
        self, difference: Posterior, plan: Plan, best: float, scale: float, composition: Composition, seed: int, scales: np.ndarray | None = None
    ) -> None:
        self.difference, self.plan, self.best, self.temperature = difference, plan, best, 0.01 * scale
        self.composition, self.scales = composition, scales
        self.normal = qmc_normals(len(composition.names) + len(composition.routes), seed)  # S x o

    def __call__(self, points: np.ndarray) -> np.ndarray:
        composition = self.composition
        planned = self.plan(points)  # b x o
        mean, std = self.difference(points)
        divisor = self.scales if self.scales is not None else 1.0
        centre = torch.as_tensor((planned + mean) / divisor, dtype=torch.float64)
        spread = torch.as_tensor(std / divisor, dtype=torch.float64)
        samples = through_routes(centre.unsqueeze(-2) + spread.unsqueeze(-2) * self.normal, len(composition.names), composition.route_parts)
        composed = compose(torch.nan_to_num(samples, nan=-1e9), composition.semantics, composition.groups)  # b x S
        values = composed.mean(dim=-1) if not math.isfinite(self.best) else log_soft_improvement(composed, self.best, self.temperature)
        return np.where(np.isfinite(planned).all(axis=1), values.numpy(), -np.inf)
