"""The paper's Algorithm 1 as a thin loop: M scrambled Sobol trials, then the acquisition (or
uniform random points for the baseline) until N trials; the answer is the best trial.

Everything a proposal depends on is the history of (point, robustness) pairs, the seed and the
trial number, so a run resumed from its recorded history proposes exactly the points an
uninterrupted run would have.
"""

from __future__ import annotations

import time
import traceback
import warnings
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from stl_lfd.optim.acquisition import propose, random_point, sobol_points
from stl_lfd.optim.task import Optimizer
from stl_lfd.stl import SpecParts


@dataclass
class Trial:
    """One finished trial (a line of `trials.jsonl`).

    Attributes:
        trial: 1-based number.
        phase: `sobol` (the M initial trials), `stl`, `pi`, `logei` or `random`.
        x: `d` parameter values.
        robustness: the objective, or None when the trial failed.
        components: the robustness of each top-level part of the spec (its text -> value),
            of which `robustness` is the composition; None when the trial failed.
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

    @property
    def satisfied(self) -> bool:
        return self.robustness is not None and self.robustness > 0

    @property
    def wall_seconds(self) -> float:
        return self.optimizer_seconds + self.rollout_seconds


@dataclass
class Outcome:
    """What the objective returns for one point: the robustness, its parts (text -> value), and
    a `payload` kept for the caller (signals)."""

    robustness: float
    payload: object = None
    components: dict[str, float] | None = None


def next_point(history: list[Trial], bounds: np.ndarray, optimizer: Optimizer, parts: SpecParts | None = None) -> tuple[np.ndarray, str]:
    """The point of trial `len(history) + 1` and the phase that chose it; method `stl` models
    each of `parts`, the spec's top-level conjuncts."""
    index = len(history)
    if index < optimizer.initial:
        return sobol_points(bounds, optimizer.initial, optimizer.seed)[index], "sobol"
    if optimizer.method == "random":
        return random_point(bounds, optimizer.seed, index), "random"
    X, Y = observations(history)
    if len(Y) == 0 or np.ptp(Y) == 0:  # every trial so far failed, or all gave the same value: nothing to model yet
        return random_point(bounds, optimizer.seed, index), "random"
    if optimizer.method == "stl":
        return _composite_point(history, X, Y, bounds, optimizer, parts), "stl"
    return propose(X, Y, bounds, optimizer.method, optimizer.xi, optimizer.seed + index), optimizer.method


def _composite_point(history: list[Trial], X: np.ndarray, Y: np.ndarray, bounds: np.ndarray, optimizer: Optimizer, parts: SpecParts | None) -> np.ndarray:
    from stl_lfd.optim.composite import propose_composite
    from stl_lfd.stl import Semantics

    composite = part_observations(history, parts.names) if parts is not None else None
    semantics = parts.semantics if parts is not None else Semantics("classic")
    if composite is None:  # trials recorded without their parts (an older run): the robustness alone
        composite, semantics = Y[:, None], Semantics("classic")
    return propose_composite(X, composite, Y, bounds, semantics, optimizer.initial, optimizer.seed + len(history))


def part_observations(history: list[Trial], names: tuple[str, ...]) -> np.ndarray | None:
    """`n x m` robustness of each part at each trial (failed trials enter with each part's worst
    value, as in `observations`), or None when a successful trial did not record its parts."""
    rows = []
    for trial in history:
        if trial.robustness is None:
            rows.append(None)
        elif trial.components is None or any(name not in trial.components for name in names):
            return None
        else:
            rows.append([trial.components[name] for name in names])
    recorded = np.array([row for row in rows if row is not None], dtype=float)
    finite = np.where(np.isfinite(recorded), recorded, np.nan)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a part infinite at every trial
        worst, best = np.nanmin(finite, axis=0), np.nanmax(finite, axis=0)
    # An infinite part (an empty window) is clipped to the values seen, so the GP sees numbers.
    worst, best = np.nan_to_num(worst, nan=0.0), np.nan_to_num(best, nan=0.0)
    return np.array([np.clip(row, worst, best) if row is not None else worst for row in rows], dtype=float)


def observations(history: list[Trial]) -> tuple[np.ndarray, np.ndarray]:
    """`n x d` points and `n` values for the GP. A failed trial enters with the worst robustness
    observed, so that the model learns to avoid its region instead of proposing it again."""
    succeeded = [trial.robustness for trial in history if trial.robustness is not None]
    if not succeeded:
        return np.empty((0, len(history[0].x) if history else 0)), np.empty(0)
    worst = min(succeeded)
    X = np.array([trial.x for trial in history])
    Y = np.array([trial.robustness if trial.robustness is not None else worst for trial in history])
    return X, Y


def run_trials(
    objective: Callable[[np.ndarray], Outcome],
    bounds: np.ndarray,
    optimizer: Optimizer,
    history: list[Trial],
    on_trial: Callable[[Trial, object], None],
    parts: SpecParts | None = None,
) -> list[Trial]:
    """Run trials until `optimizer.trials` are done, calling `on_trial(trial, payload)` after
    each (to record it) and returning the whole history. `parts` (the spec's top-level
    conjuncts) is what method `stl` models.

    A trial whose objective raises or returns a non-finite value is recorded as failed with
    its error; the loop goes on.
    """
    history = list(history)
    while len(history) < optimizer.trials:
        start = time.perf_counter()
        x, phase = next_point(history, bounds, optimizer, parts)
        chosen = time.perf_counter()
        trial = Trial(len(history) + 1, phase, x, None, optimizer_seconds=chosen - start)
        payload = None
        try:
            outcome = objective(x)
            payload = outcome.payload
            if not np.isfinite(outcome.robustness):
                raise ValueError(f"robustness is {outcome.robustness}")
            trial.robustness = float(outcome.robustness)
            trial.components = outcome.components
        except Exception as error:  # any failure of one rollout is recorded, not fatal
            trial.status, trial.error = "failed", _describe(error)
        trial.rollout_seconds = time.perf_counter() - chosen
        history.append(trial)
        on_trial(trial, payload)
    return history


def best_trial(history: list[Trial]) -> Trial | None:
    """The successful trial with the highest robustness (the earliest among equals)."""
    succeeded = [trial for trial in history if trial.robustness is not None]
    return max(succeeded, key=lambda trial: (trial.robustness, -trial.trial)) if succeeded else None


def _describe(error: Exception) -> str:
    message = str(error) or type(error).__name__
    if not hasattr(error, "exit_code"):  # not one of ours: say where it came from
        frame = traceback.extract_tb(error.__traceback__)[-1] if error.__traceback__ else None
        message = f"{type(error).__name__}: {message}" + (f" ({frame.filename.rsplit('/', 1)[-1]}:{frame.lineno})" if frame else "")
    return message
