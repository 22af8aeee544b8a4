"""Methods `pi` (the paper's probability of improvement) and `logei`: one GP on the robustness,
BoTorch's analytic acquisition maximised by multi-start L-BFGS-B.

Torch and BoTorch are imported when a proposal needs them (about 2 s): the M initial trials
(Sobol points) are handed out without them."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from stl_lfd.optim.methods.base import Proposal, Request, SobolStart
from stl_lfd.optim.methods.gp import fit_gp, maximise_acquisition, single_threaded


@dataclass(frozen=True)
class AnalyticSettings:
    """Tuning of the acquisition's maximisation.

    Attributes:
        restarts, raw_samples: L-BFGS-B starts, chosen among raw random samples.
        iterations: L-BFGS-B iterations per restart (BoTorch's default is 200).
    """

    restarts: int = 8
    raw_samples: int = 256
    # BoTorch's 200 iterations spent 2-3 s per PI proposal on phi2-shaped problems (flat log-PI,
    # ~750 evaluations); with 60 the maximum found was within 3.5 % of its PI in half the time.
    iterations: int = 60


class AnalyticSearch(SobolStart):
    """One point at a time: the maximiser of `acquisition(model, Y)` on a GP fitted to the trials."""

    parallel = False

    def __init__(self, problem, optimizer, settings: AnalyticSettings = AnalyticSettings()) -> None:
        super().__init__(problem, optimizer)
        self.settings = settings

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
    """Method `pi`, as in the paper: PI(x) = P(f(x) >= max(Y) + xi std(Y)). `xi` (the task
    file's `optimizer.xi`) is PI's margin in standard deviations of the observed robustness:
    without it PI saturates and over-exploits."""

    name = "pi"

    def acquisition(self, model, Y: np.ndarray):
        from botorch.acquisition.analytic import LogProbabilityOfImprovement

        return LogProbabilityOfImprovement(model, best_f=float(np.max(Y)) + self.optimizer.xi * float(np.std(Y)))


class LogExpectedImprovementSearch(AnalyticSearch):
    """Method `logei`: the log of expected improvement over max(Y)."""

    name = "logei"

    def acquisition(self, model, Y: np.ndarray):
        from botorch.acquisition.analytic import LogExpectedImprovement

        return LogExpectedImprovement(model, best_f=float(np.max(Y)))
