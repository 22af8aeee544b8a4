"""Method `random`: the baseline, uniform random points after the Sobol design."""

from __future__ import annotations

import numpy as np

from stl_lfd.optim.methods.base import Proposal, Request, SobolStart, random_point


class RandomSearch(SobolStart):
    """Uniform points, each determined by the run's seed and its trial index alone."""

    name = "random"

    def search(self, request: Request, X: np.ndarray, Y: np.ndarray) -> list[Proposal]:
        return [(random_point(self.problem.bounds, request.seed, index), "random") for index in request.indices]
