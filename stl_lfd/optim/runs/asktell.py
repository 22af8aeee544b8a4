"""Trials run elsewhere: `ask` hands out the next trial's reference, `tell` records the signals
its execution recorded.

A run asked for from a task file starts with trial 0, the unoptimised skill, whose signals
give the run its initial robustness. Each ask chooses the point exactly as `optimise` would
(same seed, same history, same point), checks the reference against the scene's safety
limits (an unsafe one is recorded as a failed trial at once, and the next point is chosen),
writes it to `executions/trial-NNNN/reference.csv` and records the trial as pending
(`pending.json`). Asking again before telling returns the same trial; a pending trial
survives restarts. Telling records the trial, and a killed tell is completed by the next ask
or tell (the pending record of a trial already in `trials.jsonl` is dropped).

A fleet: with `optimizer.workers` W, up to W trials are pending at once, one per robot name
(`pending.py`), proposed as `stlopt optimize --workers W` proposes them; they may be told in
any order, and a trial never told can be abandoned (recorded as failed).
"""

from __future__ import annotations

import time
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np

from stl_lfd.errors import ConfigError, ExecutionError, RunError, SignalError, WaitError
from stl_lfd.optim.inputs import TaskInputs, resolve, task_models
from stl_lfd.optim.loop import learned_from, next_points
from stl_lfd.optim.methods.base import sobol_points
from stl_lfd.optim.objective import SkillObjective, objective_for
from stl_lfd.optim.runs.directory import SIGNALS_DIR, RunDirectory, check_new_run_path
from stl_lfd.optim.runs.pending import complete, handed_out, live_pending, recorded_in_turn, to_tell
from stl_lfd.optim.runs.prepare import prepared_from
from stl_lfd.optim.runs.recorder import Recorder
from stl_lfd.optim.runs.records import MAX_ROBOT_NAME, Pending, handed_out_fingerprint, robot_name_problem
from stl_lfd.optim.runs.resume import check_resume
from stl_lfd.optim.runs.staging import StagedRun
from stl_lfd.optim.summary import ASK_TELL, Summary
from stl_lfd.optim.task import Overrides, Task
from stl_lfd.optim.trials import Outcome, Trial
from stl_lfd.signals import read_signal_csv, write_signal_csv
from stl_lfd.sim import Reference, UnsafeReference, exchange_folder, read_reference_csv, write_reference_csv
from stl_lfd.sim.command import EXECUTIONS_DIR, REFERENCE_FILE, gate, reference_path, tracking_error
from stl_lfd.sim.plausibility import check_recorded
from stl_lfd.sim.reference import Rollout, warn_if_untracked
from stl_lfd.spelling import spelled
from stl_lfd.yamlfile import shown

ABANDONED = "abandoned: never told"  # the failure recorded for a trial given up with `tell --abandon`


@dataclass(frozen=True)
class Asked:
    """A trial handed out: its number (0: the unoptimised skill), the reference CSV to execute,
    what chose it, and whether it was already pending (asked again)."""

    trial: int
    reference: Path
    phase: str
    again: bool = False
    robot: str = ""


@dataclass(frozen=True)
class Told:
    """A told trial (None for trial 0, the unoptimised skill), its robustness, and the run's
    summary after it; `waiting`, the trials still pending (it is one of them when trials
    handed out before it are not told yet)."""

    trial: Trial | None
    robustness: float | None
    summary: Summary
    waiting: tuple[Pending, ...] = ()

    @property
    def recorded(self) -> bool:
        return self.trial is None or all(entry.trial != self.trial.trial for entry in self.waiting)


def ask_new(resolved: TaskInputs, out: Path, inputs: dict[str, Any], learn_progress: Callable[[str], None] = lambda message: None) -> Asked:
    """Create the run directory `out` for a task (`resolved`: with its files read), with trial
    0 (the unoptimised skill) pending; `inputs`: the record of the task file and overrides."""
    task = resolved.task
    check_new_run_path(Path(out))
    if len(task.placements) > 1:
        raise ConfigError(f"{task.source}: stlopt ask hands out one reference per trial, so it takes one placement ('place'), not {len(task.placements)}")
    if task.model is None:
        learn_progress(f"learning the skills of {task.source.name}")
    models = task_models(resolved)
    space, objective = objective_for(resolved, models, execute=False)
    reference = objective.reference(models)
    gate(reference, objective.scene)  # nothing to record a refusal in yet: an error
    design = sobol_points(space.bounds, task.optimizer.initial, task.optimizer.seed)  # once, so that asking for them needs no torch
    with StagedRun(out) as staged:
        fingerprint = _write_reference(reference, staged.path, 0, objective.scene.gripper_opening, None)
        run = staged.commit(task, models, None, None, inputs, Pending(0, "initial", None, 0.0, time.time(), fingerprint=fingerprint), design)
    run.close()
    return Asked(0, reference_path(Path(out), 0), "initial")


def ask(
    out: Path,
    trials: int | None = None,
    file_task: Task | None = None,
    given: Overrides = Overrides(),
    on_refused: Callable[[Trial], None] = lambda trial: None,
    robot: str = "",
) -> Asked | None:
    """The trial pending on `robot` in the run in `out`, or the next one; None when the run has
    all its `trials` (default: the task's). With `file_task` and `given` (the task file and
    options named again), refuse when they ask for another run. Unsafe references become
    failed trials, passed to `on_refused`.

    Raises:
        WaitError: as many trials are pending as the task's workers allow, or the next trial is
            chosen from trials not told yet (ask again after a tell).
    """
    problem = robot_name_problem(robot)
    if problem:
        raise ConfigError(f"{spelled('robot')} {shown(robot)}: a robot's name is {MAX_ROBOT_NAME} printable characters at most; this one is {problem}")
    run = RunDirectory.open(out, for_writing=True)
    try:
        resolved = resolve(run.task())
        task = resolved.task
        if file_task is not None:
            check_resume(Path(out), resolved, run.inputs(), file_task, given)
        if trials is not None and trials != task.optimizer.trials:
            done = len(run.trials())
            if trials < done:
                raise ConfigError(f"{spelled('trials')} {trials}: the run {out} has {done} trials already; ask for at least {done}")
            task = task.with_overrides(trials=trials)
            run.write_task(task)  # the budget `tell` and `report` count with, as --resume -N extends a run
        entries = live_pending(run)
        mine = next((entry for entry in entries if entry.robot == robot and entry.told is None), None)
        if mine is not None:
            return Asked(mine.trial, reference_path(run.path, mine.trial), mine.phase, again=True, robot=robot)
        _check_room(out, task, entries)
        return _next_trial(run, replace(resolved, task=task), entries, robot, on_refused)
    finally:
        run.close()


def _check_room(out: Path, task: Task, entries: list[Pending]) -> None:
    if entries and entries[0].trial == 0:
        raise WaitError(f"{out}: trial 0, the unoptimised skill, is handed out to {entries[0].holder}; the run needs its signals before any other trial")
    if len([entry for entry in entries if entry.told is None]) >= task.optimizer.workers:
        raise WaitError(
            f"{out}: {handed_out(entries)} (the task's optimizer.workers lets {task.optimizer.workers} trial{'s' if task.optimizer.workers > 1 else ''} "
            "be handed out at once); tell one first"
        )


def _next_trial(run: RunDirectory, resolved: TaskInputs, entries: list[Pending], robot: str, on_refused: Callable[[Trial], None]) -> Asked | None:
    """Choose, check and hand out the next trial to `robot` (refused ones recorded on the way)."""
    prepared = prepared_from(run, resolved, execute=False)
    task = resolved.task
    recorder, objective = Recorder(prepared, ASK_TELL), prepared.objective
    entries = recorded_in_turn(recorder, entries)
    design = run.initial_design()
    if design is not None and design.shape != (task.optimizer.initial, len(prepared.space.bounds[0])):
        design = None
    method = prepared.search_method(design)
    while len(recorder.history) + len(entries) < task.optimizer.trials:
        start = time.perf_counter()
        number = len(recorder.history) + len(entries) + 1
        needed = learned_from(number - 1, task.optimizer)
        if len(recorder.history) < needed:
            missing = [entry for entry in entries if entry.trial <= needed and entry.told is None]
            raise WaitError(f"{run.path}: trial {number} is chosen from trials 1 to {needed}; tell {handed_out(missing)} first")
        x, phase = next_points(recorder.history, method, [entry.x for entry in entries])[0]
        try:
            reference = objective.reference(prepared.space.apply(prepared.models, x))
            gate(reference, objective.scene)
        except ExecutionError as error:  # unsafe, or no reference at all: a failed trial, as optimise records it
            seconds = time.perf_counter() - start
            trial = Trial(number, phase, x, None, "failed", str(error), optimizer_seconds=seconds)
            entries = complete(run, recorder, entries, trial, None)
            on_refused(trial)
            continue
        fingerprint = _write_reference(reference, run.path, number, objective.scene.gripper_opening, x)
        run.write_pending([*entries, Pending(number, phase, x, time.perf_counter() - start, time.time(), robot, fingerprint=fingerprint)])
        return Asked(number, reference_path(run.path, number), phase, robot=robot)
    return None


def tell(out: Path, signals_path: Path | None, failure: str | None = None, trial: int | None = None) -> Told:
    """Record a pending trial of the run in `out` (number `trial`; by default the one whose
    exchange folder holds the signals, or the only one): the signals its execution recorded,
    or (`failure`, for trials 1 and up) that the execution failed and why. A trial told before
    those handed out ahead of it is recorded once they are.

    Raises:
        RunError: nothing is pending, `trial` is not, or the signals belong to another trial.
        SignalError: the CSV is unreadable, too short, or lacks a signal the spec needs.
    """
    run = RunDirectory.open(out, for_writing=True)
    try:
        entries = live_pending(run)
        pending = to_tell(entries, Path(out), trial, signals_path)
        _check_as_handed_out(run, pending)
        resolved = resolve(run.task())
        reference = read_reference_csv(reference_path(run.path, pending.trial))
        if pending.trial == 0:
            if failure is not None:
                raise RunError(f"{out}: the unoptimised skill (trial 0) cannot be told as failed: the run needs its signals to start")
            space, objective = objective_for(resolved, run.models(), execute=False)
            return _tell_initial(run, resolved.task, space, _scored(objective, reference, Path(signals_path), run, 0), pending)
        prepared = prepared_from(run, resolved, execute=False)
        outcome = f"execution failed: {failure}" if failure is not None else _scored(prepared.objective, reference, Path(signals_path), run, pending.trial)
        seconds = max(time.time() - pending.asked, 0.0)
        told = Trial.of_outcome(pending.trial, pending.phase, pending.x, outcome, pending.optimizer_seconds, seconds)
        recorder = Recorder(prepared, ASK_TELL)
        waiting = complete(run, recorder, entries, told, None if isinstance(outcome, str) else outcome.payload, pending)
        return Told(told, told.robustness, recorder.summary(), tuple(waiting))
    finally:
        run.close()


def _tell_initial(run: RunDirectory, task: Task, space: Any, outcome: Outcome, pending: Pending) -> Told:
    if not np.isfinite(outcome.robustness):
        raise SignalError(f"{outcome.payload.source}: the robustness of the unoptimised skill is {outcome.robustness}; the run needs a finite one to start")
    write_signal_csv(outcome.payload, run.path / SIGNALS_DIR / "initial.csv")
    summary = Summary.of(task, space, float(outcome.robustness), [], max(time.time() - pending.asked, 0.0), outcome.components, ASK_TELL)
    run.write_summary(summary)
    run.clear_pending()
    return Told(None, float(outcome.robustness), summary)


def _scored(objective: SkillObjective, reference: Reference, path: Path, run: RunDirectory, trial: int) -> Outcome:
    """The signals at `path`, checked to be trial `trial`'s, scored."""
    _check_not_another_trials(path, run, trial)
    signals = read_signal_csv(path, required=("x", "y", "z"))
    check_recorded(signals, reference, objective.scene, objective.task.rate)
    errors = tracking_error(signals, reference)
    tolerance = objective.scene.tracking_tolerance
    if errors.max() > tolerance:
        _check_follows(signals, reference, errors, tolerance, run, trial)
        warn_if_untracked(Rollout(signals, errors), reference, tolerance)
    return objective.score(signals)


def _check_not_another_trials(path: Path, run: RunDirectory, trial: int) -> None:
    """Signals written into another trial's exchange folder are that trial's."""
    executions = (run.path / EXECUTIONS_DIR).resolve()
    folder = path.resolve().parent
    if folder.parent == executions and folder.name != exchange_folder(run.path, trial).name:
        raise RunError(f"{path}: belongs to {folder.name} of the run, but trial {trial} is pending; tell the signals of trial {trial}")


def _check_follows(signals: Any, reference: Reference, errors: np.ndarray, tolerance: float, run: RunDirectory, trial: int) -> None:
    """Signals that do not follow the pending reference but follow another trial's are refused."""
    for folder in sorted((run.path / EXECUTIONS_DIR).iterdir()):
        other = folder / REFERENCE_FILE
        if folder.name == exchange_folder(run.path, trial).name or not other.is_file():
            continue
        try:
            other_errors = tracking_error(signals, read_reference_csv(other))
        except SignalError:
            continue
        if other_errors.max() <= tolerance:
            raise RunError(
                f"{signals.source}: these signals follow the reference of {folder.name} (worst error {1000 * other_errors.max():.1f} mm), "
                f"not that of the pending trial {trial} ({1000 * errors.max():.1f} mm); tell the signals of trial {trial}"
            )


def _write_reference(reference: Reference, run_dir: Path, trial: int, open_width: float, x: np.ndarray | None) -> str:
    """Write the trial's reference CSV; the fingerprint of the trial as handed out."""
    path = reference_path(run_dir, trial)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_reference_csv(reference, path, open_width)
    return handed_out_fingerprint(trial, x, path.read_bytes())


def _check_as_handed_out(run: RunDirectory, pending: Pending) -> None:
    """Refuse to record a trial whose point (in pending.json) or reference CSV changed since it
    was handed out: the robustness would be recorded for a point that was not executed."""
    path = reference_path(run.path, pending.trial)
    try:
        reference = path.read_bytes()
    except OSError as error:
        raise RunError(f"{path}: cannot read trial {pending.trial}'s reference ({error.strerror or error})") from None
    if pending.fingerprint and handed_out_fingerprint(pending.trial, pending.x, reference) != pending.fingerprint:
        raise RunError(
            f"{run.path}: trial {pending.trial}'s point (pending.json) or reference ({path.relative_to(run.path)}) changed since it was handed out; "
            "restore them, or delete pending.json to hand the trial out again"
        )


__all__ = ["Asked", "Told", "UnsafeReference", "ask", "ask_new", "tell"]
