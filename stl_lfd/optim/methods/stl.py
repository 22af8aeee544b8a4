"""Method `stl`: composite Bayesian optimisation on the formula's structure.

The robustness of `a & b & c` is a fixed function of its parts' robustness, and each part is a
much smoother function of the skill parameters than the minimum of all of them. So each part
gets its own GP output, and the acquisition is maximised on the composed value by Monte Carlo
through the same semantics (Astudillo & Frazier, "Bayesian Optimization of Composite
Functions", ICML 2019): samples of the `m` parts at a point are composed into samples of the
spec's robustness, and expected improvement is taken over those (`composition.ComposedLogEI`).

The search runs in a trust region around the best trial (`trust_region.py`). While no trial
satisfies the spec and the model's last trials stalled, the next trial is the next point of
the run's Sobol sequence (`explore`). Torch is imported when a proposal needs it (about 2 s):
the M initial trials are handed out without it.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from stl_lfd.optim.methods.balance import MIN_TRIALS, balanced_values, output_scales
from stl_lfd.optim.methods.base import Composition, Proposal, Request, SobolStart, from_unit, sobol_points, to_unit
from stl_lfd.optim.methods.gp import fit_multi_output_gp, maximise_acquisition, single_threaded
from stl_lfd.optim.methods.trust_region import trust_box, trust_region_length
from stl_lfd.optim.methods.tuning import CompositeSettings
from stl_lfd.optim.trials import Trial, part_observations
from stl_lfd.stl import Semantics


@dataclass(frozen=True)
class PartsData:
    """What composite BO models: `n x m` parts and `n x r` routes of the observed trials, and
    how they compose."""

    parts: np.ndarray
    routes: np.ndarray
    semantics: Semantics
    groups: int = 1
    route_parts: tuple[int, ...] = ()
    scales: np.ndarray | None = None  # each output's scale (`balance`), None: as recorded

    @property
    def outputs(self) -> np.ndarray:
        return np.hstack([self.parts, self.routes])

    def balanced(self) -> "PartsData":
        """The same data with each output's scale (`balance.output_scales`) when there are
        several outputs to weigh against each other and `MIN_TRIALS` trials to show spreads."""
        outputs = self.outputs
        return replace(self, scales=output_scales(outputs)) if outputs.shape[1] > 1 and len(outputs) >= MIN_TRIALS else self

    def composed(self, Y: np.ndarray) -> np.ndarray:
        """`n` values the search compares trials by: their robustness `Y`, or with scales the
        composition of their balanced outputs (of the same sign)."""
        if self.scales is None:
            return Y
        return balanced_values(self.outputs, self.scales, self.parts.shape[1], self.route_parts, self.semantics, self.groups)

    @classmethod
    def observed(cls, history: list[Trial], composition: Composition | None, Y: np.ndarray) -> "PartsData":
        """The parts of `history` (`Y`: their composed values); trials recorded without their
        parts (an older run) give the robustness alone."""
        parts = part_observations(history, composition.names) if composition is not None else None
        if parts is None:
            return cls(Y[:, None], np.empty((len(Y), 0)), Semantics("classic"))
        routes = part_observations(history, composition.route_names, "routes") if composition.routes else None
        if routes is None:
            routes, route_parts = np.empty((len(Y), 0)), ()
        else:
            route_parts = composition.route_parts
        return cls(parts, routes, composition.semantics, composition.groups if parts.shape[1] > 1 else 1, route_parts)


class CompositeSearch(SobolStart):
    """Composite BO on the spec's parts (method `stl`), in a trust region, with batches chosen
    by the Kriging believer (each point after the first as if observed at its posterior mean)."""

    name = "stl"

    def __init__(self, problem, optimizer, settings: CompositeSettings | None = None) -> None:
        super().__init__(problem, optimizer)
        self.settings = settings or optimizer.tuning_for(self.name)

    def search(self, request: Request, X: np.ndarray, Y: np.ndarray) -> list[Proposal]:
        batch: list[Proposal] = []
        pending = request.pending
        data = PartsData.observed(list(request.history), self.problem.composition, Y)
        data = data.balanced() if self.settings.balance else data
        Y = data.composed(Y)
        if self.stalled(request.history, Y):
            batch.append((sobol_points(self.problem.bounds, request.first + 1, request.seed)[request.first], "explore"))
            pending = np.vstack([pending, batch[0][0]])
        if request.count > len(batch):
            points = self.composite_points(X, data, Y, request.count - len(batch), pending, request.seed_for(len(request.history)))
            batch += [(point, "stl") for point in points]
        return batch

    def stalled(self, history, Y: np.ndarray) -> bool:
        """Whether to explore next: no trial satisfies the spec yet, and each of the last
        `stall_trials` trials, chosen by the model, improved the best robustness before it by
        less than `stall_gain` of its distance to satisfaction (`Y`: the `n` observed values).

        On a spec whose robustness misleads while it is violated (phi3_strict's force part grows
        away from the hole while the shaft pushes on the holder), the model keeps proposing
        small gains away from the satisfying region; space-filling trials in between find it."""
        gain, count = self.settings.stall_gain, self.settings.stall_trials
        if np.max(Y) > 0 or len(history) <= count:
            return False
        best_before = np.maximum.accumulate(Y)[:-1]  # entry i - 1: the best before trial index i
        recent = range(len(history) - count, len(history))
        return all(history[i].phase == "stl" and Y[i] <= best_before[i - 1] + gain * abs(best_before[i - 1]) for i in recent)

    def composite_points(self, X: np.ndarray, data: PartsData, Y: np.ndarray, count: int, pending: np.ndarray, seed: int) -> np.ndarray:
        """`count x d` points: each maximises the composed log EI with the earlier ones and
        `p x d` `pending` points as if observed at their posterior mean (same hyperparameters);
        `Y`: the `n` values the search compares trials by (`PartsData.composed`).

        With routes, while the spec is violated the search spans the whole box, not the trust
        region (a part's own robustness may lead away from where a route is close to holding),
        and the acquisition's optimiser also starts near the trial where each part or route was
        best (`anchored_starts`)."""
        import torch

        from stl_lfd.optim.methods.composition import ComposedLogEI
        from stl_lfd.optim.methods.posterior import PartsPosterior

        bounds, settings = self.problem.bounds, self.settings
        encode = self.problem.features if self.problem.features is not None else (lambda points: points)
        with single_threaded():
            torch.manual_seed(seed)
            unit = to_unit(X, bounds)
            model = fit_multi_output_gp(encode(torch.as_tensor(unit, dtype=torch.float64)).numpy(), data.outputs)
            posterior = PartsPosterior(model)
            if data.route_parts and np.max(Y) <= 0:
                box, anchors = trust_box(np.full(unit.shape[1], 0.5), 1.0), best_trials(data.outputs, unit)  # the whole unit cube
            else:
                box, anchors = trust_box(unit[int(np.argmax(Y))], trust_region_length(Y, self.optimizer.initial, settings.region)), None
            executing = list(to_unit(pending, bounds)) if len(pending) else []
            chosen: list[np.ndarray] = []
            for index in range(count):
                if executing or chosen:
                    posterior = PartsPosterior(model).with_pending(encode(torch.as_tensor(np.array(executing + chosen), dtype=torch.float64)))
                acquisition = ComposedLogEI(
                    model, posterior, float(np.max(Y)), float(np.std(Y)) or 1.0, data.semantics, data.parts.shape[1], seed + index,
                    data.groups, data.route_parts, self.problem.features, data.scales,
                )  # fmt: skip
                starts = None if anchors is None else anchored_starts(acquisition, anchors, box, seed + index, settings)
                chosen.append(maximise_acquisition(acquisition, box, settings.restarts, settings.raw_samples, seed + index, starts=starts))
        return np.clip(from_unit(np.array(chosen), bounds), bounds[0], bounds[1])


def best_trials(values: np.ndarray, unit: np.ndarray) -> np.ndarray:
    """`k x d`: the points (unit cube) of the trials where some output (a part or a route,
    columns of `n x o` `values`) was at its best, each once, in trial order."""
    return unit[np.unique(np.argmax(values, axis=0))]


def anchored_starts(acquisition, anchors: np.ndarray, box: np.ndarray, seed: int, settings: CompositeSettings = CompositeSettings()):
    """`k x 1 x d` starting points for the acquisition's optimiser, one near each of the `k x d`
    `anchors`: the best of `around_anchor` normal draws around it (clipped to `box`).

    Random starts miss what is near a trial in many dimensions: in phi3_strict_final the
    trial where a route was nearly holding (4.6 N against about 110 N elsewhere) had the
    largest expected improvement around it, and none of 128 uniform starts came near it."""
    import torch

    draws_per_anchor = settings.around_anchor
    generator = torch.Generator().manual_seed(seed)
    center = torch.as_tensor(anchors, dtype=torch.float64)[:, None, :]  # k x 1 x d
    draws = center + settings.anchor_spread * torch.randn(len(anchors), draws_per_anchor, anchors.shape[1], generator=generator, dtype=torch.float64)
    draws = draws.clamp(torch.as_tensor(box[0]), torch.as_tensor(box[1]))  # k x A x d
    with torch.no_grad():
        values = acquisition(draws.reshape(-1, 1, anchors.shape[1])).reshape(len(anchors), draws_per_anchor)
    return draws[torch.arange(len(anchors)), values.argmax(dim=-1)][:, None, :]
