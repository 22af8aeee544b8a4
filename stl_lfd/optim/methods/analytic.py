"""Methods `pi` (the paper's probability of improvement) and `logei`: one GP on the robustness,
BoTorch's analytic acquisition maximised by multi-start L-BFGS-B.

Torch and BoTorch are imported when a proposal needs them (about 2 s): the M initial trials
(Sobol points) are handed out without them."""

from __future__ import annotations

import numpy as np

from stl_lfd.optim.methods.base import Proposal, Request, SobolStart
from stl_lfd.optim.methods.gp import fit_gp, maximise_acquisition, single_threaded
from stl_lfd.optim.methods.tuning import AnalyticSettings


class AnalyticSearch(SobolStart):
    """One point at a time: the maximiser of `acquisition(model, Y)` on a GP fitted to the trials."""

    parallel = False

    def __init__(self, problem, optimizer, settings: AnalyticSettings | None = None) -> None:
        super().__init__(problem, optimizer)
        self.settings = settings or optimizer.tuning_for(self.name)

    def acquisition(self, model, Y: np.ndarray):
        raise NotImplementedError

    def search(self, request: Request, X: np.ndarray, Y: np.ndarray) -> list[Proposal]:
        import torch

        seed, bounds, settings = request.seed_for(request.first), self.problem.bounds, self.settings
        torch.manual_seed(seed)
        with single_threaded():
            acquisition = self.acquisition(fit_gp(X, Y, bounds), Y)
            candidate = maximise_acquisition(acquisition, bounds, settings.restarts, settings.raw_samples, seed, settings.iterations)
        return [(np.clip(candidate, bounds[0], bounds[1]), self.name)]


class ProbabilityOfImprovement(AnalyticSearch):
    """Method `pi`, as in the paper: PI(x) = P(f(x) >= max(Y) + xi std(Y)), with `xi` from its
    settings (`tuning.ProbabilityOfImprovementSettings`, the task file's `optimizer.pi.xi`)."""

    name = "pi"

    def acquisition(self, model, Y: np.ndarray):
        from botorch.acquisition.analytic import LogProbabilityOfImprovement

        return LogProbabilityOfImprovement(model, best_f=float(np.max(Y)) + self.settings.xi * float(np.std(Y)))


class LogExpectedImprovementSearch(AnalyticSearch):
    """Method `logei`: the log of expected improvement over max(Y)."""

    name = "logei"

    def acquisition(self, model, Y: np.ndarray):
        from botorch.acquisition.analytic import LogExpectedImprovement

        return LogExpectedImprovement(model, best_f=float(np.max(Y)))
