"""How a robot follows a reference, learned from its executions: a tracking model.

A robot does not execute the plan exactly: it lags behind it, sags below it, clips its speed,
runs on a slower clock (speed scaling) or sits a constant offset away. `TrackingModel` learns
this from pairs of (reference, executed positions) and predicts the execution of a new
reference, so that a plan can be scored by what the robot will do rather than by what it was
told. Per axis, the prediction is

    executed(t) = sum_i w_i * lag_i(reference(clock * t)) + offset

where `lag_i` are first-order low-pass filters of fixed time constants (`LAGS`, the first the
identity), so that any stable lag is a linear least-squares fit, and `clock` (the reference's
seconds per executed second) is found by a one-dimensional search. Among the plan itself, the
plan plus an offset, the filter bank, and the filter bank on a warped clock, `fit` keeps the one
that predicts held-out executions best (leave one execution out), and records its error there
(`heldout_rms_`), the model's uncertainty.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from scipy.signal import lfilter

from stl_lfd.signals import SignalTable
from stl_lfd.sim.kinematic import KinematicBackend
from stl_lfd.sim.reference import Reference, Rollout
from stl_lfd.sim.scene import Scene

LAGS = (0.0, 0.03, 0.1, 0.3, 1.0)  # seconds: time constants of the filter bank (0: the reference itself)
CLOCKS = np.linspace(0.6, 1.4, 9)  # reference seconds per executed second: the clocked model's coarse grid
KINDS = ("plan", "offset", "filter", "clocked filter")  # simplest first: a tie keeps the simplest


@dataclass
class Execution:
    """One executed reference: the reference's `R` times and `R x 3` positions, and the
    execution's `T` times and `T x 3` recorded positions (both from the execution's start)."""

    reference_times: np.ndarray
    reference_positions: np.ndarray
    times: np.ndarray
    positions: np.ndarray


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

    def fit(self, executions: list[Execution]) -> "TrackingModel":
        """Choose and fit the kind that predicts held-out executions best."""
        if not executions:
            raise ValueError("a tracking model needs at least one execution")
        errors = {kind: _heldout_errors(kind, executions) for kind in KINDS}
        self.kind_ = min(KINDS, key=lambda kind: float(np.sum(errors[kind] ** 2)))
        fitted = _fit(self.kind_, executions)
        self.clock_, self.weights_, self.offsets_ = fitted.clock_, fitted.weights_, fitted.offsets_
        self.heldout_rms_, self.plan_rms_ = errors[self.kind_], errors["plan"]
        self.executions_ = len(executions)
        return self

    def predict(self, reference_times: np.ndarray, reference_positions: np.ndarray, times: np.ndarray) -> np.ndarray:
        """`T x 3` predicted positions at `times` (s, from the start) of executing the reference
        (`R` times, `R x 3` positions), or `B x T x 3` for `B x R x 3` positions."""
        positions = np.asarray(reference_positions, dtype=float)
        if positions.ndim == 3:
            return np.stack([self.predict(reference_times, batch, times) for batch in positions])
        bank = _filter_bank(reference_times, positions, times, self.clock_)  # T x 3 x L
        return np.einsum("tal,al->ta", bank, self.weights_) + self.offsets_

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


def _identity_weights() -> np.ndarray:
    """`3 x L` weights that pass the reference through unfiltered."""
    weights = np.zeros((3, len(LAGS)))
    weights[:, 0] = 1.0
    return weights


def _filter_bank(reference_times: np.ndarray, positions: np.ndarray, times: np.ndarray, clock: float) -> np.ndarray:
    """`T x 3 x L`: the reference read at `clock * times` (held at its ends), through each lag."""
    warped = np.column_stack([np.interp(clock * times, reference_times, positions[:, axis]) for axis in range(3)])
    period = float(times[1] - times[0]) if times.size > 1 else 1.0
    start = warped[:1]
    bank = np.empty(warped.shape + (len(LAGS),))
    for index, lag in enumerate(LAGS):
        if lag == 0.0:
            bank[..., index] = warped
            continue
        keep = np.exp(-period / lag)
        bank[..., index] = lfilter([1 - keep], [1, -keep], warped - start, axis=0) + start  # starts at rest
    return bank


def _fit(kind: str, executions: list[Execution]) -> TrackingModel:
    """`kind` fitted by least squares on all of `executions`."""
    if kind == "plan":
        return TrackingModel()
    clock = _best_clock(executions) if kind == "clocked filter" else 1.0
    weights, offsets, _ = _fit_at_clock(executions, clock, filters=kind != "offset")
    return TrackingModel(kind_=kind, clock_=clock, weights_=weights, offsets_=offsets)


def _best_clock(executions: list[Execution]) -> float:
    """The clock whose filter-bank fit leaves the least residual: the best of a coarse grid,
    then a bounded scalar search around it."""
    from scipy.optimize import minimize_scalar

    residual = lambda clock: _fit_at_clock(executions, clock, filters=True)[2]  # noqa: E731
    coarse = min(CLOCKS, key=residual)
    step = CLOCKS[1] - CLOCKS[0]
    found = minimize_scalar(residual, bounds=(coarse - step, coarse + step), method="bounded", options={"xatol": 1e-4})
    return float(found.x) if found.fun < residual(coarse) else float(coarse)


def _fit_at_clock(executions: list[Execution], clock: float, filters: bool) -> tuple[np.ndarray, np.ndarray, float]:
    """`3 x L` least-squares weights and `3` offsets at `clock` (the identity lag and an offset
    only, without `filters`), and the sum of squared residuals."""
    banks = [_filter_bank(e.reference_times, e.reference_positions, e.times, clock) for e in executions]
    lags = len(LAGS) if filters else 1
    weights, offsets, residual = _identity_weights(), np.zeros(3), 0.0
    for axis in range(3):
        features = np.concatenate([bank[:, axis, :lags] for bank in banks])
        target = np.concatenate([e.positions[:, axis] for e in executions])
        if filters:
            design = np.column_stack([features, np.ones(len(target))])
            solution, *_ = np.linalg.lstsq(design, target, rcond=None)
            weights[axis, :lags], offsets[axis] = solution[:lags], solution[lags]
        else:
            offsets[axis] = float(np.mean(target - features[:, 0]))
        residual += float(np.sum((target - features @ weights[axis, :lags] - offsets[axis]) ** 2))
    return weights, offsets, residual


def _heldout_errors(kind: str, executions: list[Execution]) -> np.ndarray:
    """`3` RMS errors per axis of `kind` predicting each execution fitted without it (in-sample
    with one execution)."""
    squared, count = np.zeros(3), 0
    for index, execution in enumerate(executions):
        others = executions[:index] + executions[index + 1 :] or executions
        model = _fit(kind, others)
        predicted = model.predict(execution.reference_times, execution.reference_positions, execution.times)
        squared += np.sum((predicted - execution.positions) ** 2, axis=0)
        count += len(execution.times)
    return np.sqrt(squared / count)


class PredictingBackend(KinematicBackend):
    """The kinematic backend with the robot's tracking: what `model` predicts a robot records
    when it executes the reference (orientations, gripper and carried frames as planned)."""

    def __init__(self, model: TrackingModel) -> None:
        self.model = model

    def run(self, reference: Reference, scene: Scene, rate: float, observer: Callable | None = None) -> Rollout:
        planned = super().run(reference, scene, rate, observer)
        times, columns = planned.signals.times, dict(planned.signals.columns)
        predicted = self.model.predict(reference.times, reference.positions, times)
        columns.update(zip("xyz", predicted.T))
        return Rollout(SignalTable(times, columns, source="predicted execution"), np.linalg.norm(predicted - reference.positions_at(times), axis=1))
