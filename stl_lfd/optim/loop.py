"""The paper's Algorithm 1 as a thin loop: ask the run's search method for the next batch of
points, execute them, record each trial, until N trials.

Everything a proposal depends on is the history of trials, the seed and the trial numbers, so a
run resumed from its recorded history proposes exactly the points an uninterrupted run would.
"""

from __future__ import annotations

import time
from typing import Callable, Sequence

import numpy as np

from stl_lfd.optim.methods import method_class
from stl_lfd.optim.methods.base import Problem, Proposal, Request, SearchMethod
from stl_lfd.optim.settings import Optimizer
from stl_lfd.optim.trials import Outcome, Trial, describe_error

# Starts executing a batch of `(x, trial number)` pairs and returns the function that waits for
# their outcomes (an `Outcome`, or the error message of a failed evaluation, for each).
Submit = Callable[[list[tuple[np.ndarray, int]]], Callable[[], list["Outcome | str"]]]


def search_method(optimizer: Optimizer, problem: Problem) -> SearchMethod:
    """The run's search method, by its registered name."""
    return method_class(optimizer.method)(problem, optimizer)


def batch_of(index: int, optimizer: Optimizer) -> tuple[int, int]:
    """The 0-based trial indices `[start, end)` of the batch holding trial index `index`.

    Trials run in batches of `optimizer.workers`: the M initial trials in batches of their own,
    then batches proposed together."""
    workers = optimizer.workers
    if index < optimizer.initial:
        start = index - index % workers
        return start, min(start + workers, optimizer.initial)
    start = index - (index - optimizer.initial) % workers
    return start, min(start + workers, optimizer.trials)


def learned_from(index: int, optimizer: Optimizer) -> int:
    """How many trials the proposal of trial index `index` (0-based) learns from: those before
    its batch with one worker; with several, those before the previous batch (see `next_points`)."""
    start = batch_of(index, optimizer)[0]
    return batch_of(start - 1, optimizer)[0] if optimizer.workers > 1 and start > 0 else start


def next_points(history: Sequence[Trial], method: SearchMethod, running: Sequence[np.ndarray] = ()) -> list[Proposal]:
    """The points (and phases) of the trials from `len(history) + len(running) + 1` to the end
    of their batch; `running` are the points of the trials after `history` still executing.

    With one worker every batch is one trial, proposed from the whole history. With more, a
    batch is proposed while the previous one executes: from the history before the previous
    batch, with the previous batch's points pending. Either way a batch depends only on the
    points and results of the trials before it, the seed and its first trial's number, so a run
    resumed in the middle of a batch proposes the rest of it exactly as an uninterrupted run did.
    """
    optimizer = method.optimizer
    index = len(history) + len(running)
    start, end = batch_of(index, optimizer)
    observed = learned_from(index, optimizer)
    executing = [trial.x for trial in history[observed:start]] + list(running)[: max(start - len(history), 0)]
    pending = np.array(executing).reshape(-1, method.problem.dimension)
    request = Request(history[:observed], pending, start, end - start, optimizer.seed)
    return method.propose(request)[index - start :]


def run_remaining_trials(
    objective: Callable[[np.ndarray], Outcome],
    method: SearchMethod,
    history: list[Trial],
    on_trial: Callable[[Trial, object], None],
    submit: Submit | None = None,
) -> list[Trial]:
    """Run trials until `method.optimizer.trials` are done, calling `on_trial(trial, payload)`
    after each (to record it, in trial order) and returning the whole history.

    Each batch (see `next_points`) is executed through `submit` (parallel workers), and the
    next batch is proposed while it executes; by default `objective(x)` one after the other. A
    trial whose evaluation fails or gives a non-finite value is recorded as failed with its
    error; the loop goes on.
    """
    optimizer = method.optimizer
    history = list(history)
    submit = submit or (lambda points: _done([_evaluated(objective, x) for x, _ in points]))
    pipelined = optimizer.workers > 1  # the next batch is proposed while this one executes

    def proposed(running: Sequence[np.ndarray] = ()) -> tuple[list[Proposal], float]:
        start = time.perf_counter()
        return next_points(history, method, running), time.perf_counter() - start

    def started(batch: list[Proposal], first: int) -> tuple[Callable[[], list], float]:
        """Submit `batch` (trials from number `first`): the function that waits for it, and when."""
        submitted = time.perf_counter()
        return submit([(x, first + offset) for offset, (x, _) in enumerate(batch)]), submitted

    batch, proposal_seconds = proposed() if len(history) < optimizer.trials else ([], 0.0)
    wait, submitted = started(batch, len(history) + 1) if batch else (None, 0.0)
    while batch:
        numbers = range(len(history) + 1, len(history) + 1 + len(batch))
        following, following_seconds, following_wait = [], 0.0, None
        if pipelined and numbers[-1] < optimizer.trials:
            # queued behind this batch at once: a worker that finishes its trial starts the next
            following, following_seconds = proposed([x for x, _ in batch])
            following_wait, following_submitted = started(following, numbers[-1] + 1)
        outcomes = wait()
        arrived = time.perf_counter()
        execution_seconds = arrived - submitted
        for (x, phase), number, outcome in zip(batch, numbers, outcomes):
            trial = Trial.of_outcome(number, phase, x, outcome, proposal_seconds / len(batch), execution_seconds / len(batch))
            history.append(trial)
            on_trial(trial, None if isinstance(outcome, str) else outcome.payload)
        if not pipelined and len(history) < optimizer.trials:
            following, following_seconds = proposed()
            following_wait, following_submitted = started(following, len(history) + 1)
        batch, proposal_seconds = following, following_seconds
        if batch:  # a batch queued behind this one is timed from when this one's outcomes arrived
            wait, submitted = following_wait, max(following_submitted, arrived)
    return history


def _done(outcomes: list) -> Callable[[], list]:
    return lambda: outcomes


def _evaluated(objective: Callable[[np.ndarray], Outcome], x: np.ndarray) -> "Outcome | str":
    """`objective(x)`, or the message of its error: any failure of one rollout is recorded, not fatal."""
    try:
        return objective(x)
    except Exception as error:
        return describe_error(error)
