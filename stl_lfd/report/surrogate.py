"""What a run's trials say about its parameters: a GP on the robustness, refitted from the
run directory's trials (`trials.jsonl`) as the optimiser's own GP would see them (methods `pi`
and `logei` fit this GP; `plan` and `stl` model the spec's parts apart, so no run stores it).
The report's GP slices draw it; nothing here draws."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from stl_lfd.report.run_data import RunData

SLICE_POINTS = 200


@dataclass(frozen=True)
class Slice:
    """The GP along one parameter through the best point (the others at the best's values):
    `grid` (`G` values of the parameter), and the posterior `mean` and `std` there."""

    parameter: str
    grid: np.ndarray
    mean: np.ndarray
    std: np.ndarray


class Surrogate:
    """A GP fitted on `run`'s observations (`RunData.observations`: failed trials at the worst
    robustness), in the run's parameter bounds."""

    def __init__(self, run: RunData) -> None:
        from stl_lfd.optim.methods.gp import fit_gp

        self.run = run
        self.X, self.Y = run.observations()
        self.model = fit_gp(self.X, self.Y, run.space.bounds)

    def most_relevant(self, count: int) -> list[str]:
        """The `count` parameters with the shortest lengthscales (the first ones when the kernel
        has no lengthscale per parameter)."""
        names = list(self.run.space.names)
        kernel = getattr(self.model.covar_module, "base_kernel", self.model.covar_module)
        lengthscales = kernel.lengthscale.detach().numpy().ravel() if getattr(kernel, "lengthscale", None) is not None else None
        if lengthscales is None or lengthscales.size != len(names):
            return names[:count]
        return [names[index] for index in np.argsort(lengthscales)[:count]]

    def slice_through(self, best: np.ndarray, parameter: str) -> Slice:
        """The GP along `parameter` through the point `best` (`d`)."""
        import torch

        index, bounds = list(self.run.space.names).index(parameter), self.run.space.bounds
        grid = np.linspace(bounds[0, index], bounds[1, index], SLICE_POINTS)
        points = np.repeat(best[None], grid.size, axis=0)
        points[:, index] = grid
        with torch.no_grad():
            posterior = self.model.posterior(torch.as_tensor(points, dtype=torch.float64))
            mean = posterior.mean.numpy().ravel()
            std = posterior.variance.clamp_min(0).sqrt().numpy().ravel()
        return Slice(parameter, grid, mean, std)
