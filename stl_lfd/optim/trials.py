"""Trials and what they observe: `Trial` (a line of `trials.jsonl`), `Outcome` (what executing a
point gave), and the observations a search method learns from."""

from __future__ import annotations

import traceback
import warnings
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np


@dataclass
class Outcome:
    """What the objective returns for one point: the robustness, its parts and routes (text ->
    value), and a `payload` kept for the caller (signals)."""

    robustness: float
    payload: object = None
    components: dict[str, float] | None = None
    routes: dict[str, float] | None = None


@dataclass
class Trial:
    """One finished trial (a line of `trials.jsonl`).

    Attributes:
        trial: 1-based number.
        phase: what chose x: `sobol` (the M initial trials), `stl`, `pi`, `logei` or `random`;
            with method `plan`, `design` (its M initial trials) then `plan`; `explore` for
            the space-filling trials of method `stl` while it stalls.
        x: `d` parameter values.
        robustness: the objective, or None when the trial failed.
        components: the robustness of each top-level part of the spec (its text -> value),
            of which `robustness` is the composition; None when the trial failed.
        routes: the robustness of each of the spec's routes (`SpecParts.routes`), formulas
            that imply a part; None when the spec has none or the trial failed.
        status: `ok` or `failed` (then `error` says why).
        optimizer_seconds: time spent choosing x (GP fit and acquisition).
        rollout_seconds: time spent executing and evaluating x.
    """

    trial: int
    phase: str
    x: np.ndarray
    robustness: float | None
    status: str = "ok"
    error: str | None = None
    optimizer_seconds: float = 0.0
    rollout_seconds: float = 0.0
    parameters: dict[str, float] = field(default_factory=dict)
    components: dict[str, float] | None = None
    routes: dict[str, float] | None = None

    @property
    def satisfied(self) -> bool:
        return self.robustness is not None and self.robustness > 0

    @property
    def wall_seconds(self) -> float:
        return self.optimizer_seconds + self.rollout_seconds

    @classmethod
    def of_outcome(
        cls, number: int, phase: str, x: np.ndarray, outcome: "Outcome | str", optimizer_seconds: float = 0.0, rollout_seconds: float = 0.0
    ) -> "Trial":
        """Trial `number` from what its execution gave: an `Outcome`, or the message of a failure.
        A non-finite robustness is a failed trial too. The one place where the trial loop and
        `tell` turn an execution into a trial."""
        trial = cls(number, phase, x, None, optimizer_seconds=optimizer_seconds, rollout_seconds=rollout_seconds)
        if isinstance(outcome, str):
            trial.status, trial.error = "failed", outcome
        elif not np.isfinite(outcome.robustness):
            trial.status, trial.error = "failed", f"robustness is {outcome.robustness}"
        else:
            trial.robustness, trial.components, trial.routes = float(outcome.robustness), outcome.components, outcome.routes
        return trial


def best_so_far(robustness: np.ndarray) -> np.ndarray:
    """The best robustness after each trial (`N`), given each trial's (`N`, NaN for a failed
    trial): NaN before the first successful trial. Every figure and table of runs uses this."""
    values = np.asarray(robustness, dtype=float)
    return np.fmax.accumulate(values) if values.size else values


def robustness_of(history: Sequence[Trial]) -> np.ndarray:
    """Each trial's robustness (`N`), NaN for a failed trial."""
    return np.array([np.nan if trial.robustness is None else trial.robustness for trial in history], dtype=float)


def best_trial(history: Sequence[Trial]) -> Trial | None:
    """The successful trial with the highest robustness (the earliest among equals)."""
    succeeded = [trial for trial in history if trial.robustness is not None]
    return max(succeeded, key=lambda trial: (trial.robustness, -trial.trial)) if succeeded else None


def describe_error(error: Exception) -> str:
    """One line for a failed trial: our errors' own message; others also say where they came from."""
    message = str(error) or type(error).__name__
    if not hasattr(error, "exit_code"):  # not one of ours: say where it came from
        frame = traceback.extract_tb(error.__traceback__)[-1] if error.__traceback__ else None
        message = f"{type(error).__name__}: {message}" + (f" ({frame.filename.rsplit('/', 1)[-1]}:{frame.lineno})" if frame else "")
    return message


# A value further than this many scales (the interquartile range, or the median's magnitude if
# larger) beyond the quartiles is absurd: wrong by orders of magnitude, not merely bad.
OUTLIER_SCALES = 1e4


def without_outliers(values: np.ndarray) -> np.ndarray:
    """`values` (`n`, or `n x m` column by column) with absurd ones (a robustness of -1e300, or
    +1e308, from a broken recording) replaced by the worst ordinary value, as failed trials
    enter: one such value would otherwise stretch the GP's standardisation until every other
    value looks the same. A part that saturates has a tiny interquartile range, so the scale is
    at least the median's magnitude, and a collision's force of -78 N among margins of 2 N is
    bad, not absurd: ordinary runs never come near the bound."""
    values = np.asarray(values, dtype=float)
    if len(values) < 4:
        return values
    lower, median, upper = np.percentile(values, [25, 50, 75], axis=0)
    scale = np.maximum(upper - lower, np.abs(median))
    # a column at exactly zero so far has no scale to judge by: its first move is news, not absurd
    absurd = (scale > 1e-9) & ((values < lower - OUTLIER_SCALES * scale) | (values > upper + OUTLIER_SCALES * scale))
    if not absurd.any():
        return values
    worst = np.min(np.where(absurd, np.inf, values), axis=0)
    return np.where(absurd, worst, values)


def observations(history: Sequence[Trial]) -> tuple[np.ndarray, np.ndarray]:
    """`n x d` points and `n` values for the GP. A failed trial enters with the worst robustness
    observed, so that the model learns to avoid its region instead of proposing it again;
    outliers are clipped (`without_outliers`)."""
    succeeded = [trial.robustness for trial in history if trial.robustness is not None]
    if not succeeded:
        return np.empty((0, len(history[0].x) if history else 0)), np.empty(0)
    worst = min(succeeded)
    X = np.array([trial.x for trial in history])
    Y = np.array([trial.robustness if trial.robustness is not None else worst for trial in history])
    return X, without_outliers(Y)


def part_observations(history: Sequence[Trial], names: tuple[str, ...], recorded_as: str = "components") -> np.ndarray | None:
    """`n x m` robustness of each part at each trial (failed trials enter with each part's worst
    value, as in `observations`), or None when a successful trial did not record its parts.
    With `recorded_as="routes"`, the same for the spec's routes."""
    rows = []
    for trial in history:
        values = getattr(trial, recorded_as)
        if trial.robustness is None:
            rows.append(None)
        elif values is None or any(name not in values for name in names):
            return None
        else:
            rows.append([values[name] for name in names])
    recorded = np.array([row for row in rows if row is not None], dtype=float)
    finite = np.where(np.isfinite(recorded), recorded, np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a part infinite at every trial
        worst, best = np.nanmin(finite, axis=0), np.nanmax(finite, axis=0)
    # An infinite part (an empty window) is clipped to the values seen, so the GP sees numbers.
    worst, best = np.nan_to_num(worst, nan=0.0), np.nan_to_num(best, nan=0.0)
    return without_outliers(np.array([np.clip(row, worst, best) if row is not None else worst for row in rows], dtype=float))
