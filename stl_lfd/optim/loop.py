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
from typing import Callable, Sequence

import numpy as np

from stl_lfd.optim.acquisition import propose, random_point, sobol_points
from stl_lfd.optim.task import Optimizer
from stl_lfd.stl import SpecParts

STALL_GAIN = 0.1  # an improvement below this fraction of the distance to satisfaction is a stall
STALL_TRIALS = 2  # stalled model-based trials in a row before a space-filling one


@dataclass
class Trial:
    """One finished trial (a line of `trials.jsonl`).

    Attributes:
        trial: 1-based number.
        phase: `sobol` (the M initial trials), `stl`, `pi`, `logei` or `random`; with method
            `plan`, `design` (its M initial trials) then `plan`; `explore` for
            the space-filling trials of method `stl` while it stalls (see `stalled`).
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


@dataclass
class Outcome:
    """What the objective returns for one point: the robustness, its parts and routes (text ->
    value), and a `payload` kept for the caller (signals)."""

    robustness: float
    payload: object = None
    components: dict[str, float] | None = None
    routes: dict[str, float] | None = None


def next_point(
    history: list[Trial],
    bounds: np.ndarray,
    optimizer: Optimizer,
    parts: SpecParts | None = None,
    initial_design: np.ndarray | None = None,
    features: Callable | None = None,
    plan: Callable | None = None,
) -> tuple[np.ndarray, str]:
    """The point of trial `len(history) + 1` and the phase that chose it; method `stl` models
    each of `parts`, the spec's top-level conjuncts, as functions of `features` of the points
    (`features.path_features`; None: the points themselves); method `plan` models each
    part's difference from its `plan` (`planned.Plan`)."""
    return next_points(history, bounds, optimizer, parts, initial_design=initial_design, features=features, plan=plan)[0]


def next_points(
    history: list[Trial],
    bounds: np.ndarray,
    optimizer: Optimizer,
    parts: SpecParts | None = None,
    running: Sequence[np.ndarray] = (),
    initial_design: np.ndarray | None = None,
    features: Callable | None = None,
    plan: Callable | None = None,
) -> list[tuple[np.ndarray, str]]:
    """The points (and phases) of the trials from `len(history) + len(running) + 1` to the end
    of their batch; `running` are the points of the trials after `history` still executing;
    `initial_design`, when known, the `M x d` `sobol_points(bounds, M, seed)` (computing them
    imports torch, about 2 s for a command).

    Trials run in batches of `optimizer.workers`: the M initial trials in batches of their own,
    then batches proposed together. With one worker every batch is one trial, proposed from
    the whole history. With more, a batch is proposed while the previous one executes: from the
    history before the previous batch, with the previous batch's points (and the batch's own
    earlier points) pending. Either way a batch depends only on the points and results of the
    trials before it, the seed and its first trial's number, so a run resumed in the middle of
    a batch proposes the rest of it exactly as an uninterrupted run did.
    """
    index = len(history) + len(running)
    start, end = batch_of(index, optimizer)
    if optimizer.method == "plan":
        return _planned_batch(history, running, bounds, optimizer, parts, plan, features)[index - start :]
    if index < optimizer.initial:
        design = sobol_points(bounds, optimizer.initial, optimizer.seed) if initial_design is None else initial_design
        return [(point, "sobol") for point in design[index:end]]
    if optimizer.method == "random":
        return [(random_point(bounds, optimizer.seed, trial), "random") for trial in range(index, end)]
    observed = batch_of(start - 1, optimizer)[0] if optimizer.workers > 1 else start
    before = history[:observed]
    pending = np.array([trial.x for trial in history[observed:start]] + list(running)[: max(start - len(history), 0)]).reshape(-1, bounds.shape[1])
    X, Y = observations(before)
    if len(Y) == 0 or np.ptp(Y) == 0:  # every trial so far failed, or all gave the same value: nothing to model yet
        return [(random_point(bounds, optimizer.seed, trial), "random") for trial in range(index, end)]
    if optimizer.method == "stl":
        batch: list[tuple[np.ndarray, str]] = []
        if stalled(before, Y):
            batch.append((sobol_points(bounds, start + 1, optimizer.seed)[start], "explore"))
            pending = np.vstack([pending, batch[0][0]])
        if end - start > len(batch):
            points = _composite_points(before, X, Y, bounds, optimizer, parts, end - start - len(batch), pending, features)
            batch += [(point, "stl") for point in points]
        return batch[index - start :]
    return [(propose(X, Y, bounds, optimizer.method, optimizer.xi, optimizer.seed + index), optimizer.method)]


def stalled(history: list[Trial], Y: np.ndarray) -> bool:
    """Whether method `stl` explores next: no trial satisfies the spec yet, and each of the last
    `STALL_TRIALS` trials, chosen by the model, improved the best robustness before it by less
    than `STALL_GAIN` of its distance to satisfaction (`Y`: the `n` observed values of
    `history`).

    Then the next trial is the next point of the run's scrambled Sobol sequence. On a spec
    whose robustness misleads while it is violated (phi3_strict's force part grows away from
    the hole while the shaft pushes on the holder), the model keeps proposing small gains
    away from the satisfying region; space-filling trials in between find it."""
    if np.max(Y) > 0 or len(history) <= STALL_TRIALS:
        return False
    best_before = np.maximum.accumulate(Y)[:-1]  # entry i - 1: the best before trial index i
    recent = range(len(history) - STALL_TRIALS, len(history))
    return all(history[i].phase == "stl" and Y[i] <= best_before[i - 1] + STALL_GAIN * abs(best_before[i - 1]) for i in recent)


def batch_of(index: int, optimizer: Optimizer) -> tuple[int, int]:
    """The 0-based trial indices `[start, end)` of the batch holding trial index `index`."""
    workers = optimizer.workers
    if index < optimizer.initial:
        start = index - index % workers
        return start, min(start + workers, optimizer.initial)
    start = index - (index - optimizer.initial) % workers
    return start, min(start + workers, optimizer.trials)


def _composite_points(
    history: list[Trial],
    X: np.ndarray,
    Y: np.ndarray,
    bounds: np.ndarray,
    optimizer: Optimizer,
    parts: SpecParts | None,
    count: int,
    pending: np.ndarray,
    features: Callable | None,
) -> np.ndarray:
    from stl_lfd.optim.composite import propose_composite
    from stl_lfd.stl import Semantics

    composite = part_observations(history, parts.names) if parts is not None else None
    semantics = parts.semantics if parts is not None else Semantics("classic")
    if composite is None:  # trials recorded without their parts (an older run): the robustness alone
        composite, semantics = Y[:, None], Semantics("classic")
    groups = getattr(parts, "groups", 1) if composite.shape[1] > 1 else 1
    routes = getattr(parts, "routes", ())  # none without parts, or with several placements
    route_values = part_observations(history, tuple(route.name for route in routes), "routes") if routes else None
    points = propose_composite(
        X, composite, Y, bounds, semantics, optimizer.initial, optimizer.seed + len(history), count, pending if len(pending) else None, groups,
        None if route_values is None else (route_values, tuple(route.part for route in routes)), features,
    )  # fmt: skip
    return points[None] if count == 1 else points


def _planned_batch(
    history: list[Trial],
    running: Sequence[np.ndarray],
    bounds: np.ndarray,
    optimizer: Optimizer,
    parts: SpecParts | None,
    plan: Callable | None,
    features: Callable | None,
) -> list[tuple[np.ndarray, str]]:
    """Method `plan`'s batch holding trial index `len(history) + len(running)`: `design`
    trials while in the initial M, `plan` trials after, each chosen with the batch's earlier
    points and the points still executing pending (as `next_points` describes)."""
    index = len(history) + len(running)
    start, end = batch_of(index, optimizer)
    observed = batch_of(start - 1, optimizer)[0] if optimizer.workers > 1 and start > 0 else start
    pending = [trial.x for trial in history[observed:start]] + list(running)[: max(start - len(history), 0)]
    batch: list[tuple[np.ndarray, str]] = []
    for number in range(start, end):
        design = number < optimizer.initial
        point = _planned_point(history[:observed], bounds, optimizer, parts, plan, features, design, number, pending + [x for x, _ in batch])
        batch.append((point, "design" if design else "plan"))
    return batch


def _planned_point(
    history: list[Trial],
    bounds: np.ndarray,
    optimizer: Optimizer,
    parts: SpecParts | None,
    plan: Callable | None,
    features: Callable | None,
    design: bool,
    number: int,
    pending: list[np.ndarray],
) -> np.ndarray:
    """Method `plan`'s point for trial index `number` (one of the initial `design`'s or not),
    modelled on the successful trials of `history` (a failed one has no difference from its
    plan to learn), with `pending` points executing or chosen for the same batch."""
    from stl_lfd.optim.planned import propose_planned

    if plan is None or parts is None:
        raise ValueError("method plan needs the spec's parts and the plan of a point")
    routes = getattr(parts, "routes", ())
    succeeded = [trial for trial in history if trial.robustness is not None]
    outputs = np.empty((0, len(parts.names) + len(routes)))
    if succeeded:
        values = part_observations(succeeded, tuple(parts.names))
        route_values = part_observations(succeeded, tuple(route.name for route in routes), "routes") if routes else np.empty((len(succeeded), 0))
        if values is None or route_values is None:
            raise ValueError("method plan needs every trial's parts (trials.jsonl 'components')")
        outputs = np.hstack([values, route_values])
    X = np.array([trial.x for trial in succeeded]).reshape(-1, bounds.shape[1])
    Y = np.array([trial.robustness for trial in succeeded])
    tried = np.array([trial.x for trial in history] + pending).reshape(-1, bounds.shape[1])
    return propose_planned(
        X, outputs, Y, bounds, parts.semantics, len(parts.names), plan, optimizer.seed, optimizer.seed + number,
        getattr(parts, "groups", 1), tuple(route.part for route in routes), features, design, tried,
        np.array(pending).reshape(-1, bounds.shape[1]),
    )  # fmt: skip


def part_observations(history: list[Trial], names: tuple[str, ...], recorded_as: str = "components") -> np.ndarray | None:
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


# Starts executing a batch of `(x, trial number)` pairs and returns the function that waits for
# their outcomes (an `Outcome`, or the error message of a failed evaluation, for each).
Submit = Callable[[list[tuple[np.ndarray, int]]], Callable[[], list["Outcome | str"]]]


def run_trials(
    objective: Callable[[np.ndarray], Outcome],
    bounds: np.ndarray,
    optimizer: Optimizer,
    history: list[Trial],
    on_trial: Callable[[Trial, object], None],
    parts: SpecParts | None = None,
    submit: Submit | None = None,
    features: Callable | None = None,
    plan: Callable | None = None,
) -> list[Trial]:
    """Run trials until `optimizer.trials` are done, calling `on_trial(trial, payload)` after
    each (to record it, in trial order) and returning the whole history. `parts` (the spec's
    top-level conjuncts) is what method `stl` models, on `features` of the points.

    Each batch (see `next_points`) is executed through `submit` (parallel workers), and the
    next batch is proposed while it executes; by default `objective(x)` one after the other. A
    trial whose evaluation fails or gives a non-finite value is recorded as failed with its
    error; the loop goes on.
    """
    history = list(history)
    submit = submit or (lambda points: _done([_evaluated(objective, x) for x, _ in points]))
    pipelined = optimizer.workers > 1  # the next batch is proposed while this one executes

    def started(batch: list[tuple[np.ndarray, str]], first: int) -> tuple[Callable[[], list], float]:
        """Submit `batch` (trials from number `first`): the function that waits for it, and when."""
        submitted = time.perf_counter()
        return submit([(x, first + offset) for offset, (x, _) in enumerate(batch)]), submitted

    start = time.perf_counter()
    batch = next_points(history, bounds, optimizer, parts, features=features, plan=plan) if len(history) < optimizer.trials else []
    proposal_seconds = time.perf_counter() - start
    wait, submitted = started(batch, len(history) + 1) if batch else (None, 0.0)
    while batch:
        numbers = range(len(history) + 1, len(history) + 1 + len(batch))
        following, following_seconds, following_wait = [], 0.0, None
        if pipelined and numbers[-1] < optimizer.trials:
            start = time.perf_counter()
            following = next_points(history, bounds, optimizer, parts, [x for x, _ in batch], features=features, plan=plan)
            following_seconds = time.perf_counter() - start
        outcomes = wait()
        execution_seconds = time.perf_counter() - submitted
        if following:  # the workers start on the next batch before this one is recorded
            following_wait, following_submitted = started(following, numbers[-1] + 1)
        for (x, phase), number, outcome in zip(batch, numbers, outcomes):
            trial = Trial(number, phase, x, None, optimizer_seconds=proposal_seconds / len(batch), rollout_seconds=execution_seconds / len(batch))
            payload = None
            if isinstance(outcome, str):
                trial.status, trial.error = "failed", outcome
            elif not np.isfinite(outcome.robustness):
                trial.status, trial.error, payload = "failed", f"robustness is {outcome.robustness}", outcome.payload
            else:
                trial.robustness, trial.components, trial.routes, payload = float(outcome.robustness), outcome.components, outcome.routes, outcome.payload
            history.append(trial)
            on_trial(trial, payload)
        if not pipelined and len(history) < optimizer.trials:
            start = time.perf_counter()
            following = next_points(history, bounds, optimizer, parts, features=features, plan=plan)
            following_seconds = time.perf_counter() - start
            following_wait, following_submitted = started(following, len(history) + 1)
        batch, proposal_seconds = following, following_seconds
        if batch:
            wait, submitted = following_wait, following_submitted
    return history


def _done(outcomes: list) -> Callable[[], list]:
    return lambda: outcomes


def _evaluated(objective: Callable[[np.ndarray], Outcome], x: np.ndarray) -> "Outcome | str":
    """`objective(x)`, or the message of its error: any failure of one rollout is recorded, not fatal."""
    try:
        return objective(x)
    except Exception as error:
        return describe_error(error)


def best_trial(history: list[Trial]) -> Trial | None:
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
