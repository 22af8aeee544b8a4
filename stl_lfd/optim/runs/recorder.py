"""Recording a run's trials as they finish (`Recorder`, shared by the trial loop and `tell`),
and `finish_run`: the remaining trials of a prepared run, on one or several workers."""

from __future__ import annotations

import time
from typing import Any, Callable

import numpy as np

from stl_lfd.optim.loop import run_remaining_trials
from stl_lfd.optim.runs.prepare import PreparedRun
from stl_lfd.optim.runs.workers import ObjectiveFactory
from stl_lfd.optim.summary import Summary, execution_of
from stl_lfd.optim.trials import Outcome, Trial, best_trial


class Recorder:
    """Records each finished trial of a run: its line and signals, the best models when it
    improves on the best so far, and the summary."""

    def __init__(self, prepared: PreparedRun, executed_by: str | None = None) -> None:
        """`executed_by`: how the trials it records are executed (default: as the task executes
        them, `execution_of`); a run whose trials were executed in more ways says so."""
        self.prepared = prepared
        self.executed_by = combined_execution(prepared.summary.executed_by, executed_by or execution_of(prepared.task))
        self.history = list(prepared.history)
        self.best = best_trial(self.history)
        self.wall_seconds = prepared.summary.wall_seconds
        if self.best is not None and not prepared.run.has_best_models():
            prepared.run.write_best_models(prepared.space.apply(prepared.models, self.best.x))

    def record(self, trial: Trial, signals: Any, seconds: float) -> None:
        """Record `trial` (its `signals` may be None), which took `seconds` of wall time."""
        run, space = self.prepared.run, self.prepared.space
        trial.parameters = space.as_dict(trial.x)
        run.append_trial(trial, signals)
        if trial.robustness is not None and (self.best is None or trial.robustness > self.best.robustness):
            self.best = trial
            run.write_best_models(space.apply(self.prepared.models, trial.x))
        self.history.append(trial)
        self.wall_seconds += seconds
        run.write_summary(self.summary())

    def summary(self) -> Summary:
        prepared = self.prepared
        initial = prepared.summary
        executed_by = self.executed_by if len(self.history) > len(prepared.history) else initial.executed_by or None
        return Summary.of(prepared.task, prepared.space, initial.initial_robustness, self.history, self.wall_seconds, initial.initial_components, executed_by)


def combined_execution(before: str, now: str) -> str:
    """How a run's trials were executed, `before` (what its summary says) and `now`:
    `pybullet, then stlopt ask/tell` when they differ."""
    if not before or before == now or before.endswith(f", then {now}"):
        return before or now
    return f"{before}, then {now}"


def finish_run(prepared: PreparedRun, on_trial: Callable[[Trial, Trial | None], None] = lambda trial, best: None, ray: str | None = None) -> Summary:
    """Run the remaining trials of `prepared`, recording each (then `on_trial(trial, best)`);
    returns the final summary. `ray`: run the trials on this Ray cluster (`ray_workers.connect`)
    instead of in this process or local worker processes."""
    recorder = Recorder(prepared)
    mark = time.perf_counter()

    def record(trial: Trial, signals: Any) -> None:
        nonlocal mark
        now = time.perf_counter()
        recorder.record(trial, signals, now - mark)
        mark = now
        on_trial(trial, recorder.best)

    def objective(x: np.ndarray) -> Outcome:
        return prepared.objective(x, trial=len(recorder.history) + 1)

    pool = trial_pool(prepared, ray) if len(prepared.history) < prepared.task.optimizer.trials else None
    try:
        run_remaining_trials(objective, prepared.search_method(), prepared.history, record, pool)
    except BaseException:
        if pool is not None:
            pool.stop()  # now: the trials in flight are lost, as with one worker
        raise
    if pool is not None:
        pool.close()
    if len(recorder.history) == len(prepared.history):  # nothing ran (a finished run resumed): nothing changes
        return prepared.summary
    prepared.refresh_tracking(recorder.history)
    recorder.wall_seconds += time.perf_counter() - mark
    summary = recorder.summary()
    prepared.run.write_summary(summary)
    return summary


def trial_pool(prepared: PreparedRun, ray: str | None) -> Any:
    """Who executes the trials of `prepared` besides this process: Ray tasks on the cluster
    `ray`, local worker processes when the task has several workers, or nobody (None)."""
    workers = prepared.task.optimizer.workers
    make_objective = ObjectiveFactory(prepared.inputs, prepared.models, prepared.run.path)
    if ray is not None:
        from stl_lfd.optim.runs.ray_workers import RayPool

        return RayPool(make_objective, ray)
    if workers > 1:
        from stl_lfd.optim.runs.workers import WorkerPool

        return WorkerPool(make_objective, workers)
    return None
