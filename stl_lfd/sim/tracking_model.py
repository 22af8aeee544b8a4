"""How a robot follows a reference, learned from its executions: a tracking model.

A robot does not execute the plan exactly: it lags behind it, sags below it, clips its speed,
runs on a slower clock (speed scaling) or sits a constant offset away. `TrackingModel` learns
this from pairs of (reference, executed positions) and predicts the execution of a new
reference, so that a plan can be scored by what the robot will do rather than by what it was
told. Per axis, the prediction is

    executed(t) - start = sum_i w_i * lag_i(reference(clock * t) - start) + offset

where `start` is the reference's first position, `lag_i` are first-order low-pass filters of
fixed time constants (`LAGS`, the first the identity) starting at rest, so that any stable lag
is a linear least-squares fit, and `clock` (the reference's seconds per executed second) is
found by a one-dimensional search. Among the plan itself, the
plan plus an offset, the filter bank, and the filter bank on a warped clock, `fit` keeps the one
that predicts held-out executions best (leave one execution out, from each execution's normal
equations; the clock is searched on all of them), and records its error there
(`heldout_rms_`), the model's uncertainty.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.signal import lfilter

from stl_lfd.signals import SignalTable
from stl_lfd.sim.backend import Capabilities
from stl_lfd.sim.grasp_model import GraspModel
from stl_lfd.sim.kinematic import KinematicBackend
from stl_lfd.sim.reference import Reference, Rollout, recording_times
from stl_lfd.sim.scene import Scene

LAGS = (0.0, 0.03, 0.1, 0.2, 0.3, 0.5, 1.0)  # seconds: time constants of the filter bank (0: the reference itself)
CLOCKS = np.linspace(0.6, 1.4, 9)  # reference seconds per executed second: the clocked model's coarse grid
KINDS = ("plan", "offset", "filter", "clocked filter")  # simplest first
# A kind with more parameters is kept only when it predicts better by more than this fraction
# (with one execution its error is in-sample, where more parameters always fit a little better).
BETTER_BY = 0.01


@dataclass
class Execution:
    """One executed reference: the reference's `R` times and `R x 3` positions, and the
    execution's `T` times and `T x 3` recorded positions (both from the execution's start)."""

    reference_times: np.ndarray
    reference_positions: np.ndarray
    times: np.ndarray
    positions: np.ndarray
    # (kind, clock) -> its normal equations on the reference's own clock and the coarse grid's,
    # computed once (every refit of a run uses them again)
    equations: dict = field(default_factory=dict, repr=False, compare=False)


@dataclass
class TrackingModel:
    """A model of how a robot follows a reference (see the module's docstring).

    Attributes (after `fit`):
        kind_: which of `KINDS` predicts held-out executions best.
        clock_: reference seconds per executed second (1 but for the clocked filter).
        weights_: `3 x len(LAGS)` filter weights per axis; offsets_: `3` offsets (m).
        heldout_rms_: `3` RMS errors (m) per axis of the chosen kind on executions it did not
            see (in-sample with a single execution); plan_rms_: the same of the plan itself.
        executions_: the number of executions it was fitted on.
    """

    kind_: str = "plan"
    clock_: float = 1.0
    weights_: np.ndarray = field(default_factory=lambda: _identity_weights())
    offsets_: np.ndarray = field(default_factory=lambda: np.zeros(3))
    heldout_rms_: np.ndarray = field(default_factory=lambda: np.zeros(3))
    plan_rms_: np.ndarray = field(default_factory=lambda: np.zeros(3))
    executions_: int = 0

    def fit(self, executions: list[Execution], plan_within: float = 0.0) -> "TrackingModel":
        """Choose and fit the kind that predicts held-out executions best; the plan itself,
        without fitting the others, when it predicts every axis within `plan_within` (m RMS)."""
        if not executions:
            raise ValueError("a tracking model needs at least one execution")
        plan = _Fit("plan", executions, 1.0)
        if np.max(plan.heldout_rms) <= plan_within:
            fits = {"plan": plan}
        else:
            clocks = {"plan": 1.0, "offset": 1.0, "filter": 1.0, "clocked filter": _best_clock(executions)}
            fits = {kind: plan if kind == "plan" else _Fit(kind, executions, clocks[kind]) for kind in KINDS}
        self.kind_ = _simplest_best(fits)
        chosen = fits[self.kind_]
        self.clock_, self.weights_, self.offsets_ = chosen.clock, chosen.weights, chosen.offsets
        self.heldout_rms_, self.plan_rms_ = chosen.heldout_rms, fits["plan"].heldout_rms
        self.executions_ = len(executions)
        return self

    def predict(self, reference_times: np.ndarray, reference_positions: np.ndarray, times: np.ndarray) -> np.ndarray:
        """`T x 3` predicted positions at `times` (s, from the start) of executing the reference
        (`R` times, `R x 3` positions), or `B x T x 3` for `B x R x 3` positions."""
        positions = np.asarray(reference_positions, dtype=float)
        if positions.ndim == 3:
            return np.stack([self.predict(reference_times, batch, times) for batch in positions])
        bank = _filter_bank(reference_times, positions, times, self.clock_)  # T x 3 x L, from the start
        return positions[0] + np.einsum("tal,al->ta", bank, self.weights_) + self.offsets_

    def to_dict(self) -> dict:
        """Plain values, for JSON."""
        return {
            "kind": self.kind_,
            "clock": self.clock_,
            "weights": self.weights_.tolist(),
            "offsets": self.offsets_.tolist(),
            "heldout_rms": self.heldout_rms_.tolist(),
            "plan_rms": self.plan_rms_.tolist(),
            "executions": self.executions_,
        }

    @classmethod
    def from_dict(cls, data: dict) -> "TrackingModel":
        return cls(
            kind_=str(data["kind"]),
            clock_=float(data["clock"]),
            weights_=np.asarray(data["weights"], dtype=float),
            offsets_=np.asarray(data["offsets"], dtype=float),
            heldout_rms_=np.asarray(data["heldout_rms"], dtype=float),
            plan_rms_=np.asarray(data["plan_rms"], dtype=float),
            executions_=int(data["executions"]),
        )


def _simplest_best(fits: dict[str, "_Fit"]) -> str:
    """The simplest kind whose squared error is within BETTER_BY of the best one's."""
    errors = {kind: float(np.sum(fit.heldout_rms**2)) for kind, fit in fits.items()}
    best = min(errors.values())
    return next(kind for kind in KINDS if kind in errors and errors[kind] <= best * (1 + BETTER_BY) + 1e-18)


def _identity_weights() -> np.ndarray:
    """`3 x L` weights that pass the reference through unfiltered."""
    weights = np.zeros((3, len(LAGS)))
    weights[:, 0] = 1.0
    return weights


def _filter_bank(reference_times: np.ndarray, positions: np.ndarray, times: np.ndarray, clock: float) -> np.ndarray:
    """`T x 3 x L`: the reference read at `clock * times` (held at its ends), less its first
    position, through each lag (starting at rest)."""
    warped = np.column_stack([np.interp(clock * times, reference_times, positions[:, axis] - positions[0, axis]) for axis in range(3)])
    period = float(times[1] - times[0]) if times.size > 1 else 1.0
    bank = np.empty(warped.shape + (len(LAGS),))
    for index, lag in enumerate(LAGS):
        keep = np.exp(-period / lag) if lag > 0 else 0.0
        bank[..., index] = lfilter([1 - keep], [1, -keep], warped, axis=0) if lag > 0 else warped
    return bank


class _Fit:
    """One kind fitted by least squares at one clock, on all executions (`weights`, `offsets`,
    `residual`: the sum of squared residuals) and, with `heldout`, leaving each out in turn
    (`heldout_rms`: `3` RMS errors per axis; in-sample with one execution), from each
    execution's normal equations."""

    def __init__(self, kind: str, executions: list[Execution], clock: float, heldout: bool = True) -> None:
        self.clock = clock
        equations = [_normal_equations(kind, execution, clock) for execution in executions]  # each: 3 x (G, b, c, n)
        self.weights, self.offsets, self.residual = _identity_weights(), np.zeros(3), 0.0
        squared, count = np.zeros(3), sum(len(execution.times) for execution in executions)
        for axis in range(3):
            per_execution = [equation[axis] for equation in equations]
            gram, moment = sum(e[0] for e in per_execution), sum(e[1] for e in per_execution)
            solution = _solve(gram, moment)
            self._store(kind, axis, solution)
            self.residual += _squared_error(solution, gram, moment, sum(e[2] for e in per_execution))
            if not heldout:
                continue
            for own_gram, own_moment, own_square, _ in per_execution:
                held = _solve(gram - own_gram, moment - own_moment) if len(executions) > 1 else solution
                squared[axis] += _squared_error(held, own_gram, own_moment, own_square)
        self.heldout_rms = np.sqrt(squared / count)

    def _store(self, kind: str, axis: int, solution: np.ndarray) -> None:
        if kind == "offset":
            self.offsets[axis] = solution[0]
        elif kind in ("filter", "clocked filter"):
            self.weights[axis], self.offsets[axis] = solution[:-1], solution[-1]


def _squared_error(weights: np.ndarray, gram: np.ndarray, moment: np.ndarray, square: float) -> float:
    """`|D w - y|^2` from the normal equations (`D'D`, `D'y`, `y'y`)."""
    return max(square - 2 * weights @ moment + weights @ gram @ weights, 0.0)


def _normal_equations(kind: str, execution: Execution, clock: float) -> list[tuple[np.ndarray, np.ndarray, float, int]]:
    """Per axis, `(D'D, D'y, y'y, T)` of `kind`'s least-squares problem `D w = y` on one
    execution: y the execution relative to the reference's start, less the reference itself
    where the reference passes through unweighted (plan, offset). On the reference's own clock
    and the clocks of the coarse grid they are computed once per execution."""
    kind = "filter" if kind == "clocked filter" else kind
    if (kind, clock) in execution.equations:
        return execution.equations[kind, clock]
    bank = _filter_bank(execution.reference_times, execution.reference_positions, execution.times, clock)
    if clock != 1.0 and clock not in CLOCKS:
        return _equations_of(kind, bank, execution)
    kinds = ("plan", "offset", "filter") if clock == 1.0 else ("filter",)
    execution.equations.update({(name, clock): _equations_of(name, bank, execution) for name in kinds})
    return execution.equations[kind, clock]


def _equations_of(kind: str, bank: np.ndarray, execution: Execution) -> list[tuple[np.ndarray, np.ndarray, float, int]]:
    relative = execution.positions - execution.reference_positions[0]
    equations = []
    for axis in range(3):
        features = bank[:, axis, :]
        if kind in ("filter", "clocked filter"):
            design, target = np.column_stack([features, np.ones(len(features))]), relative[:, axis]
        else:
            columns = 1 if kind == "offset" else 0
            design, target = np.ones((len(features), columns)), relative[:, axis] - features[:, 0]
        equations.append((design.T @ design, design.T @ target, float(target @ target), len(target)))
    return equations


def _solve(gram: np.ndarray, moment: np.ndarray) -> np.ndarray:
    """The least-squares solution of normal equations `gram w = moment`. With more than one
    unknown (the filter bank, then the offset) the filter weights are kept non-negative: a
    mixture of lags, which is what a stable, non-overshooting servo is; unconstrained weights
    of the (nearly collinear) lags fit the noise of a few executions with huge opposite values."""
    if gram.size == 0:
        return np.zeros(0)
    if len(gram) == 1:
        return np.array([moment[0] / gram[0, 0]]) if gram[0, 0] > 0 else np.zeros(1)
    from scipy.optimize import nnls

    # The offset (last unknown) is eliminated: for given weights its best value is known.
    lags, cross, offset_gram = gram[:-1, :-1], gram[:-1, -1], gram[-1, -1]
    reduced = lags - np.outer(cross, cross) / offset_gram
    reduced_moment = moment[:-1] - cross * moment[-1] / offset_gram
    reduced += np.eye(len(reduced)) * 1e-12 * max(np.trace(reduced), 1e-300)
    try:
        upper = np.linalg.cholesky(reduced).T  # reduced = upper' upper
        weights, _ = nnls(upper, np.linalg.solve(upper.T, reduced_moment))
    except np.linalg.LinAlgError:  # lags that carry nothing at all (a reference that never moves)
        weights = np.eye(1, len(reduced))[0]  # the reference itself
    offset = (moment[-1] - cross @ weights) / offset_gram
    return np.append(weights, offset)


def _best_clock(executions: list[Execution]) -> float:
    """The clock whose filter-bank fit leaves the least residual on all executions: the best of
    a coarse grid, then a bounded scalar search around it."""
    from scipy.optimize import minimize_scalar

    def residual(clock: float) -> float:
        return _Fit("filter", executions, clock, heldout=False).residual

    coarse = min(CLOCKS, key=residual)
    step = CLOCKS[1] - CLOCKS[0]
    found = minimize_scalar(residual, bounds=(coarse - step, coarse + step), method="bounded", options={"xatol": 1e-4})
    return float(found.x) if found.fun < residual(coarse) else float(coarse)


class PredictingBackend(KinematicBackend):
    """The kinematic backend with the robot's tracking: it records what `model` predicts a robot
    does when it executes the reference. The hand's positions are the prediction; orientation,
    gripper, grasps and releases follow the robot's clock (`model.clock_`), and carried objects
    move with the predicted hand, where `grasp` (a `GraspModel`) says they sit in it."""

    capabilities = Capabilities()  # a prediction of a robot, not the plan itself

    def __init__(self, model: TrackingModel, grasp: GraspModel | None = None) -> None:
        self.model = model
        self.in_hand = grasp.in_hand_ if grasp is not None else None

    def run(self, reference: Reference, scene: Scene, rate: float, observer: Callable | None = None) -> Rollout:
        predicted = super().run(self.predicted(reference, rate), scene, rate, observer)
        # a prediction, not an execution: its departure from the reference is no tracking error to warn about
        return Rollout(SignalTable(predicted.signals.times, predicted.signals.columns, source="predicted execution"), np.zeros(predicted.signals.samples))

    def predicted(self, reference: Reference, rate: float) -> Reference:
        """The execution the model predicts, as a reference sampled at `rate` over the same
        duration: what the kinematic backend then records as is."""
        times = recording_times(reference.duration, rate)
        clock = self.model.clock_
        on_clock = np.clip(clock * times, reference.times[0], reference.times[-1])

        def labels(values: np.ndarray | None) -> np.ndarray | None:
            return None if values is None else np.asarray(values)[np.searchsorted(reference.times, on_clock, side="right") - 1]

        return Reference(
            times,
            self.model.predict(reference.times, reference.positions, times),
            gripper=None if reference.gripper is None else np.interp(on_clock, reference.times, reference.gripper),
            events=tuple((time / clock, action) for time, action in reference.events if time / clock <= times[-1]),
            skills=labels(reference.skills),
            states=labels(reference.states),
            orientations=None if reference.orientations is None else reference.orientations_at(on_clock),
        )
