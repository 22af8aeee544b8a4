"""A run made ready for its trials: started from a task (the unoptimised skill executed and
the run directory created in one step), or reopened from its run directory; `open_run`, either
of them as `stlopt optimize` asks (with `--resume` or without)."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from functools import cached_property
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from stl_lfd.errors import RunError
from stl_lfd.files import write_atomically
from stl_lfd.hsmm import HSMM
from stl_lfd.optim.features import path_features
from stl_lfd.optim.inputs import TaskInputs, resolve, task_models
from stl_lfd.optim.loop import search_method
from stl_lfd.optim.methods.base import Planner, Problem, SearchMethod
from stl_lfd.optim.objective import SkillObjective, objective_for
from stl_lfd.optim.runs.directory import RunDirectory, check_new_run_path
from stl_lfd.optim.runs.resume import check_resume, inputs_record
from stl_lfd.optim.runs.staging import StagedRun
from stl_lfd.optim.runs.store import RunStore
from stl_lfd.optim.space import SearchSpace
from stl_lfd.optim.summary import Summary
from stl_lfd.optim.task import Overrides, Task
from stl_lfd.optim.tracking_fit import TRACKING_FILE, RunTracking
from stl_lfd.optim.trials import Outcome, Trial
from stl_lfd.signals import SignalTable
from stl_lfd.sim.registry import check_command_for
from stl_lfd.stl import ast


@dataclass
class PreparedRun:
    """A run ready for its remaining trials: its task's inputs (read once), where it records
    (`RunStore`), the skills, the parameter space, the objective, the trials so far and the
    summary."""

    inputs: TaskInputs
    run: RunStore
    models: dict[str, HSMM]
    space: SearchSpace
    objective: SkillObjective
    history: list[Trial]
    summary: Summary
    initial_signals: SignalTable | None = None  # when the run started in this process

    @property
    def task(self) -> Task:
        return self.inputs.task

    @cached_property
    def tracking(self) -> RunTracking | None:
        """How the robot follows its references, learned from the run's executions; None where
        the backend plays the plan back or the run has several object placements."""
        if self.objective.plays_the_plan or len(self.objective.placed) != 1:
            return None
        return RunTracking(self.objective, self.models, self.space, self.run.recorded_signals, self.run.path)

    def problem(self, initial_design: np.ndarray | None = None) -> Problem:
        """What the search method searches: the bounds, the spec's parts, what a GP sees of a
        point (`features.path_features`), and the plan of a point (method `plan`'s prior), through
        the robot's tracking model where the backend does not play the plan back."""
        features = path_features(self.space, self.models)
        planner = Planner(self.objective.plan_score(), self.tracking.plan_score if self.tracking is not None else None)
        return Problem(self.space.bounds, self.objective.composition, features, planner, initial_design)

    def refresh_tracking(self, history: list[Trial]) -> None:
        """Fit a run's tracking model (`tracking.json`) on all of `history`, when the run
        learned one: its record then covers every trial, the last ones included."""
        if self.tracking is not None and self.run.path is not None and (self.run.path / TRACKING_FILE).is_file():
            self.tracking.model(history)

    def search_method(self, initial_design: np.ndarray | None = None) -> SearchMethod:
        return search_method(self.task.optimizer, self.problem(initial_design))

    def close(self) -> None:
        """Release the run directory's write lock and the simulator (ending the process does too)."""
        self.run.close()
        self.objective.close()

    def __enter__(self) -> "PreparedRun":
        return self

    def __exit__(self, *exception: object) -> None:
        self.close()


def prepare_objective(inputs: TaskInputs, models: dict[str, HSMM]) -> tuple[SearchSpace, SkillObjective, Outcome, Summary]:
    """`objective_for`, then the unoptimised skill executed once: the space, the objective (which
    the caller closes), the unoptimised outcome and the summary of a run with no trial yet."""
    task = inputs.task
    space, objective = objective_for(inputs, models)
    try:
        start = time.perf_counter()
        initial = objective.evaluate(models)
    except BaseException:
        objective.close()
        raise
    summary = Summary.of(task, space, float(initial.robustness), [], time.perf_counter() - start, initial.components)
    return space, objective, initial, summary


def start_run(
    task: Task | TaskInputs,
    out: Path,
    learn_progress: Callable[[str], None] = lambda message: None,
    inputs: dict[str, Any] | None = None,
    models: dict[str, HSMM] | None = None,
    spec: ast.Spec | None = None,
    files: Mapping[str, str] | None = None,
) -> PreparedRun:
    """Check `out`, learn or load the model, check the spec, execute the unoptimised skill, then
    create the run directory with all of that in it. `task`: a task, or its inputs already
    resolved (`optim.inputs.resolve`); `inputs` is the record of the task file and command-line
    overrides (`resume.inputs_record`; default: `task` as its own file).

    From Python objects: `models` instead of the task's, `spec` instead of reading `task.spec`,
    and `files` (name -> text) written into the run directory with the rest, for task paths
    that point into it."""
    check_new_run_path(Path(out))
    if isinstance(task, TaskInputs) and spec is not None:
        raise TypeError("start_run: resolved inputs already hold their spec; give `spec` to resolve() instead")
    resolved = task if isinstance(task, TaskInputs) else resolve(task, spec)
    task = resolved.task
    if models is None:
        if task.model is None:
            learn_progress(f"learning the skills of {task.source.name}")
        models = task_models(resolved)
    space, objective = objective_for(resolved, models)
    try:
        with StagedRun(out) as staged:
            for name, text in (files or {}).items():
                write_atomically(staged.path / name, text)
            objective.exchange_in(staged.path)  # the unoptimised skill's execution is part of the new run
            start = time.perf_counter()
            initial = objective.evaluate(models, trial=0)
            summary = Summary.of(task, space, float(initial.robustness), [], time.perf_counter() - start, initial.components)
            run = staged.commit(task, models, initial.payload, summary, inputs if inputs is not None else inputs_record(task, Overrides(), resolved))
        objective.exchange_in(run.path)
    except BaseException:
        objective.close()
        raise
    return PreparedRun(resolved, run, models, space, objective, [], summary, initial.payload)


def open_run(
    file_task: Task,
    given: Overrides,
    out: Path,
    resume: bool = False,
    learn_progress: Callable[[str], None] = lambda message: None,
    ray: str | None = None,
    watch_head: bool = False,
) -> PreparedRun:
    """The run in `out` of `file_task` (the task as its file gives it) with the settings `given`
    on top: reopened where it stopped (`resume`: checked to be that run, extended to
    `given.trials`), or started (`start_run`, which tells `learn_progress` when it learns the
    skills). With `ray`, that Ray cluster is joined first (`ray_workers.connect`; `watch_head`:
    the process ends when the cluster's head is lost), so that a cluster that cannot be reached
    leaves nothing behind."""
    if ray is not None:
        from stl_lfd.optim.runs.ray_workers import connect

        connect(ray, watch=watch_head)
    if resume:
        return resume_run(out, given.trials, file_task, given)
    given, note = given.fitted_to(file_task)
    if note:
        learn_progress(note)
    task = given.applied_to(file_task)
    check_command_for(task.backend, given.command)
    resolved = resolve(task)
    return start_run(resolved, out, learn_progress, inputs_record(file_task, given, resolved))


def resume_run(out: Path, trials: int | None = None, file_task: Task | None = None, given: Overrides = Overrides()) -> PreparedRun:
    """Reopen a run directory to finish it (or extend it to `trials` in total), holding its
    write lock. With `file_task` (the task file named on the command line) and `given` (the
    options given again), refuse when they ask for another run than the recorded one."""
    run = RunDirectory.open(out, for_writing=True)
    try:
        return _reopen(run, out, trials, file_task, given)
    except BaseException:
        run.close()
        raise


def _reopen(run: RunDirectory, out: Path, trials: int | None, file_task: Task | None, given: Overrides) -> PreparedRun:
    resolved = resolve(run.task())
    task = resolved.task
    if file_task is not None:
        check_resume(Path(out), resolved, run.inputs(), file_task, given)
    if trials is not None:
        task = task.with_overrides(trials=trials)
    pending = [entry for entry in run.pending() if entry.told is None]
    if pending:
        handed = ", ".join(f"trial {entry.trial} to {entry.holder}" for entry in pending)
        raise RunError(f"{out}: stlopt ask handed out {handed}, not told yet; tell its signals first (stlopt tell {out} SIGNALS.csv --trial N)")
    missing = run.missing_signals()
    if missing:
        listed = ", ".join(str(path.relative_to(run.path)) for path in missing)
        raise RunError(
            f"{out}: the recorded signals of finished trials are missing ({listed}); the run cannot go on without them: restore them, or start a new run"
        )
    return prepared_from(run, replace(resolved, task=task))


def prepared_from(run: RunDirectory, task: Task | TaskInputs, execute: bool = True) -> PreparedRun:
    """An existing run ready for more trials (its `task`, or the task's inputs already
    resolved): its models, space, objective (executing in the run's folder, or only scoring
    unless `execute`), checked history and summary."""
    resolved = task if isinstance(task, TaskInputs) else resolve(task)
    models = run.models()
    space, objective = objective_for(resolved, models, execute=execute)
    objective.exchange_in(run.path)
    history = run.trials()
    if any(len(trial.x) != space.dimension for trial in history):
        raise RunError(f"{run.path / 'trials.jsonl'}: damaged (the recorded points do not have the task's {space.dimension} parameters)")
    return PreparedRun(resolved, run, models, space, objective, history, run.summary())
