"""Method `plan`: composite BO with the plan as the prior.

Before a trial executes, the tool already knows what it will ask the robot to do: the
reference retrieved from the adapted skill. Scored as it stands (the kinematic backend, about
40-90 ms), this plan gives the robustness of every part of the spec without a robot trial. The
execution differs from the plan by what the plan cannot know: tracking errors, and contact
(the plan records no force). So each part's GP models the difference between execution and
plan, starting from none, and a part's sample at a point is the plan's value plus a sample of
the difference; the samples are composed through the spec's semantics as in method `stl`, and
expected improvement is taken over them.

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

from typing import Hashable, Sequence

import numpy as np
import torch
from torch.quasirandom import SobolEngine

from stl_lfd.optim.methods.balance import MIN_TRIALS, balanced_values, output_scales
from stl_lfd.optim.methods.base import Proposal, Request, SearchMethod, from_unit, to_unit
from stl_lfd.optim.methods.composition import compose, through_routes
from stl_lfd.optim.methods.gp import single_threaded
from stl_lfd.optim.methods.plan_model import Plan, Scorer, difference_posterior
from stl_lfd.optim.methods.tuning import PlanSettings
from stl_lfd.optim.trials import Trial, part_observations


class PlanSearch(SearchMethod):
    """Method `plan` (see the module docstring). The first trial is the best point of the plan
    search; the other trials of the initial design (`design`) spread over the points the plan
    says satisfy the spec (`spread_point`), so that the parts the plan cannot see are sampled
    across the box, as Sobol trials would; after them, the acquisition on plan + difference."""

    name = "plan"

    def __init__(self, problem, optimizer, settings: PlanSettings | None = None) -> None:
        super().__init__(problem, optimizer)
        if problem.planner is None or problem.composition is None:
            raise ValueError("method plan needs the spec's parts and the plan of a point")
        self.settings = settings or optimizer.tuning_for(self.name)
        self.plan = Plan(problem.planner.plan, problem.bounds)
        self._tracked: tuple[Hashable, Plan] | None = None  # the plan through the latest tracking model

    def propose(self, request: Request) -> list[Proposal]:
        """Each point of the batch chosen with the batch's earlier points pending too."""
        batch: list[Proposal] = []
        for index in request.indices:
            design = index < self.optimizer.initial
            pending = np.vstack([request.pending, *[x[None] for x, _ in batch]]) if batch else request.pending
            batch.append((self.point(request, index, design, pending), "design" if design else "plan"))
        return batch

    def point(self, request: Request, index: int, design: bool, pending: np.ndarray) -> np.ndarray:
        """The point of trial index `index`, modelled on the successful trials of the request's
        history (a failed one has no difference from its plan to learn)."""
        bounds, composition = self.problem.bounds, self.problem.composition
        succeeded = [trial for trial in request.history if trial.robustness is not None]
        X = np.array([trial.x for trial in succeeded]).reshape(-1, self.problem.dimension)
        Y = np.array([trial.robustness for trial in succeeded])
        tried = np.array([trial.x for trial in request.history] + list(pending)).reshape(-1, self.problem.dimension)
        with single_threaded():
            plan = self.plan_for(request.history)
            unit, tried = to_unit(X, bounds), to_unit(tried, bounds)
            if design and len(tried):
                scales = self.scales(self.observed_outputs(succeeded), plan, request.seed) if self.settings.balance else None
                return from_unit(self.spread_point(self.pool(request.seed), tried, plan, scales), bounds)
            outputs = self.observed_outputs(succeeded)
            scales = self.scales(outputs, plan, request.seed)
            difference = difference_posterior(unit, outputs - plan(unit) if len(X) else outputs, self.problem.features)
            if scales is not None:
                Y = balanced_values(outputs, scales, len(composition.names), composition.route_parts, composition.semantics, composition.groups)
            best = float(np.max(Y)) if len(Y) else -np.inf
            scale = float(np.std(Y)) if len(Y) > 1 and np.std(Y) > 0 else 1.0
            score = Scorer(difference, plan, best, scale, composition, request.seed_for(index), scales)
            candidates, values = self.search(score, unit[np.argmax(Y, keepdims=True)] if len(Y) else unit[:0], request.seed, request.seed_for(index))
            values = np.where(within(candidates, tried, 1e-9), -np.inf, values)  # a point already executed would teach nothing new
            if len(pending):
                values = np.where(within(candidates, to_unit(pending, bounds), self.settings.pending_spread), -np.inf, values)
        return np.clip(from_unit(candidates[int(np.argmax(values))], bounds), bounds[0], bounds[1])

    def scales(self, outputs: np.ndarray, plan: Plan, seed: int) -> np.ndarray | None:
        """Each output's scale (`balance.output_scales`): the spread of the `n x o` observed
        `outputs`, or before `MIN_TRIALS` trials the spread of the plans over the pool; None
        without balancing, or with a single output."""
        if not self.settings.balance or outputs.shape[1] < 2:
            return None
        return output_scales(outputs if len(outputs) >= MIN_TRIALS else plan(self.pool(seed)))

    def plan_for(self, history: Sequence[Trial]) -> Plan:
        """The plan of a point as the robot will execute it: through the tracking model learned
        from `history` (`Planner.as_executed`), or the plan itself where the robot executes it."""
        key, score = self.problem.planner.as_executed(history)
        if key is None:  # the robot follows the plan
            return self.plan
        if self._tracked is None or self._tracked[0] != key:
            self._tracked = (key, Plan(score, self.problem.bounds))
        return self._tracked[1]

    def search(self, score: Scorer, best_trial: np.ndarray, seed: int, trial_seed: int) -> tuple[np.ndarray, np.ndarray]:
        """Candidates (`c x d`, unit cube) and their scores: the pool, then the refinement
        rounds around the best candidates and `best_trial` (`1 x d`, or none before a trial;
        its neighbourhood may rank lower than the pool's best)."""
        candidates = self.pool(seed)
        values = score(candidates)
        generator = np.random.default_rng([seed, trial_seed])
        rounds = self.settings.rounds if len(best_trial) else self.settings.first_rounds
        for spread in rounds.spreads:
            centres = np.vstack([best_trial, candidates[np.argsort(-values, kind="stable")[: rounds.centres]]])
            draws = np.clip(centres[:, None, :] + spread * generator.standard_normal((len(centres), rounds.draws, candidates.shape[1])), 0.0, 1.0)
            draws = draws.reshape(-1, candidates.shape[1])
            candidates, values = np.vstack([candidates, draws]), np.concatenate([values, score(draws)])
        return candidates, values

    def observed_outputs(self, succeeded: Sequence[Trial]) -> np.ndarray:
        """`n x o`: the recorded robustness of each part, then route, at the successful trials."""
        composition = self.problem.composition
        if not succeeded:
            return np.empty((0, len(composition.names) + len(composition.routes)))
        values = part_observations(succeeded, composition.names)
        routes = part_observations(succeeded, composition.route_names, "routes") if composition.routes else np.empty((len(succeeded), 0))
        if values is None or routes is None:
            raise ValueError("method plan needs every trial's parts (trials.jsonl 'components')")
        return np.hstack([values, routes])

    def spread_point(self, pool: np.ndarray, tried: np.ndarray, plan: Plan, scales: np.ndarray | None = None) -> np.ndarray:
        """The point of `pool` (`P x d`, unit cube) farthest from the `n x d` `tried` points among
        the untried ones whose `plan` satisfies the spec (or, when none is left, among the best
        quarter by plan, its outputs divided by `scales`)."""
        composition = self.problem.composition
        planned = plan(pool) / (scales if scales is not None else 1.0)
        samples = through_routes(torch.as_tensor(np.nan_to_num(planned, nan=-1e9)), len(composition.names), composition.route_parts)
        values = compose(samples, composition.semantics, composition.groups).numpy()
        values = np.where(np.isfinite(planned).all(axis=1), values, -np.inf)
        distance = np.min(np.linalg.norm(pool[:, None, :] - tried[None, :, :], axis=-1), axis=1)
        untried = distance > 1e-9
        eligible = untried & (values > 0)
        if not eligible.any():
            eligible = untried & (values >= np.quantile(values[untried], 0.75))
        return pool[int(np.argmax(np.where(eligible, distance, -np.inf)))]

    def pool(self, seed: int) -> np.ndarray:
        """The run's `pool x d` candidates: scrambled Sobol points of the unit cube."""
        return SobolEngine(self.problem.dimension, scramble=True, seed=seed).draw(self.settings.pool, dtype=torch.float64).numpy()


def within(points: np.ndarray, others: np.ndarray, distance: float) -> np.ndarray:
    """`b` flags: whether each of `b x d` `points` is within `distance` (largest coordinate
    difference) of one of `k x d` `others`."""
    if not len(others):
        return np.zeros(len(points), dtype=bool)
    return np.min(np.abs(points[:, None, :] - others[None, :, :]).max(axis=-1), axis=1) < distance
