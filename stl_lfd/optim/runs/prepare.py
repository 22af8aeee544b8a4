"""An optimisation run from a task file: prepare (model, space, objective, initial skill), then
the trial loop, recording everything in the run directory as it goes."""

from __future__ import annotations

import copy
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Mapping

import numpy as np

from stl_lfd.errors import ConfigError, ExecutionError, RunError, SignalError, SpecError
from stl_lfd.files import write_atomically
from stl_lfd.hsmm import HSMM, learn_from_folder, load_model
from stl_lfd.optim.loop import Outcome, Trial, best_trial, run_trials
from stl_lfd.optim.resume import check_resume, inputs_record
from stl_lfd.optim.rundir import RunDirectory, StagedRun, check_new_run_path
from stl_lfd.optim.space import SearchSpace, build_search_space
from stl_lfd.optim.summary import Summary
from stl_lfd.optim.task import SINGLE_SKILL, Task
from stl_lfd.signals import SignalTable
from stl_lfd.sim import Backend, CommandBackend, Reference, Scene, execute, load_scene, new_backend
from stl_lfd.skill.behaviour import Behaviour, behaviour_models, load_behaviour, reference_for
from stl_lfd.stl import Semantics, SpecParts, ast, load_spec, split_spec


@dataclass(frozen=True)
class Placements:
    """The parts of a trial at several object placements: the spec's parts at each placement
    (`names` in placement order, `placement i (...): part`), composed by the spec's semantics
    within a placement and by the minimum over the `groups` placements. Offers what the
    optimiser reads of `SpecParts`, so that composite BO models each part at each placement
    with its own GP output."""

    names: tuple[str, ...]
    semantics: Semantics
    groups: int


class SkillObjective:
    """x -> adapted models -> (behaviour) reference -> rollout -> robustness of the recorded
    signals and of the spec's top-level parts (payload: the signals). It owns its backend (one
    simulated world for all its rollouts) until `close`; without a backend (`execute=False` in
    `objective_for`) it only scores signals recorded elsewhere.

    With several object placements (`task.placements`), a trial executes once per placement and
    its robustness is the worst; its parts are then the spec's parts at each placement, and its
    payload the signals of the worst placement."""

    def __init__(
        self, models: dict[str, HSMM], space: SearchSpace, task: Task, behaviour: Behaviour | None, scene: Scene, parts: SpecParts, backend: Backend | None
    ) -> None:
        self.models, self.space, self.task, self.behaviour, self.parts = models, space, task, behaviour, parts
        self.scenes = [scene.place(placement, str(task.source)) for placement in task.placements] or [scene]
        self.scene = self.scenes[0]
        self.backend = backend
        # The parts the optimiser models: the spec's, or the spec's at each placement.
        self.composition: SpecParts | Placements = parts if len(self.scenes) == 1 else placement_parts(parts, task.placements)

    def close(self) -> None:
        if self.backend is not None:
            self.backend.close()

    def exchange_in(self, folder: Path) -> None:
        """Write the command backend's exchange folders in `folder` (the run directory)."""
        if isinstance(self.backend, CommandBackend):
            self.backend.folder = Path(folder)

    def __call__(self, x: np.ndarray, trial: int = 0) -> Outcome:
        return self.evaluate(self.space.apply(self.models, x), trial)

    def planned(self) -> "SkillObjective":
        """This objective on the kinematic backend: it scores the plan (the reference itself)."""
        from stl_lfd.sim.kinematic import KinematicBackend

        plan = copy.copy(self)
        plan.backend = KinematicBackend()
        return plan

    def reference(self, models: dict[str, HSMM], scene: Scene | None = None) -> Reference:
        """What executing `models` means: the behaviour's (or single skill's) reference, for the
        object frames of `scene` (default: the first placement)."""
        scene = self.scene if scene is None else scene
        return reference_for(models, self.behaviour, scene.gripper_opening, self.task.duration, scene.frame_poses)

    def evaluate(self, models: dict[str, HSMM], trial: int = 0) -> Outcome:
        """Execute `models` as trial `trial` (0: the unoptimised skill) and score the signals."""
        if self.backend is None:
            raise ExecutionError("this objective only scores signals recorded elsewhere (it has no backend)")
        if isinstance(self.backend, CommandBackend):
            self.backend.trial = trial
        outcomes = [self.score(execute(self.reference(models, scene), scene, self.backend, self.task.rate).signals) for scene in self.scenes]
        if len(outcomes) == 1:
            return outcomes[0]
        worst = min(outcomes, key=lambda outcome: outcome.robustness)
        values = [value for outcome in outcomes for value in outcome.components.values()]
        return Outcome(worst.robustness, worst.payload, dict(zip(self.composition.names, values)))

    def score(self, signals: SignalTable) -> Outcome:
        """The robustness of recorded `signals`, and of each of the spec's parts."""
        missing = sorted(self.parts.signals - set(signals.columns))
        if missing:
            raise SignalError(f"{signals.source}: no column {', '.join(missing)}, which the spec needs")
        # The spec is evaluated once, part by part; composing the parts is exactly its robustness.
        values = self.parts(signals.columns, signals.times)
        routes = self.parts.route_values(signals.columns, signals.times) or None
        return Outcome(self.parts.compose(values), signals, dict(zip(self.parts.names, values.tolist())), routes)


@dataclass
class PreparedRun:
    task: Task
    run: RunDirectory
    models: dict[str, HSMM]
    space: SearchSpace
    objective: SkillObjective
    history: list[Trial]
    summary: Summary
    initial_signals: SignalTable | None = None  # when the run started in this process

    def features(self):
        """What method `stl`'s GP sees of a point (`features.path_features`), or None."""
        from stl_lfd.optim.features import path_features

        return path_features(self.space, self.models)

    def plan(self):
        """Method `plan`'s prior (`planned.Plan`: the plan's robustness of each part and route
        of the spec at a point), or None for the other methods."""
        if self.task.optimizer.method != "plan":
            return None
        from stl_lfd.optim.planned import Plan

        planned, routes = self.objective.planned(), getattr(self.objective.composition, "routes", ())

        def score(x: np.ndarray) -> np.ndarray:
            outcome = planned(x)
            values = list(outcome.components.values()) + [outcome.routes[route.name] for route in routes]
            return np.array(values, dtype=float)

        return Plan(score, self.space.bounds)

    def close(self) -> None:
        """Release the run directory's write lock and the simulator (ending the process does too)."""
        self.run.close()
        self.objective.close()

    def __enter__(self) -> "PreparedRun":
        return self

    def __exit__(self, *exception: object) -> None:
        self.close()


def task_models(task: Task) -> dict[str, HSMM]:
    """The skills of a task: learned from its demos, loaded, or those of its behaviour."""
    if task.behaviour is not None:
        return behaviour_models(load_behaviour(task.behaviour))
    if task.demos is not None:
        return {SINGLE_SKILL: learn_from_folder(task.demos, task.states)[0]}
    return {SINGLE_SKILL: load_model(task.model)}


def objective_for(task: Task, models: dict[str, HSMM], spec: ast.Spec | None = None, execute: bool = True) -> tuple[SearchSpace, SkillObjective]:
    """The parameter space and the objective of `task` (with `spec` instead of reading
    `task.spec` when given; with a backend of its own unless not `execute`); spec problems are
    found here, before any trial: unknown signals, and windows that reach past the rollout
    duration."""
    if len(task.placements) > 1 and task.backend == "command":
        raise ConfigError(f"{task.source}: several placements need a simulated backend (the command backend executes one reference per trial)")
    space = build_search_space(models, task.parameters, task.source)
    spec = load_spec(task.spec) if spec is None else spec
    parts = split_spec(spec, task.semantics, task.nu, source=str(task.spec))
    horizon = max(function.horizon for function in parts.functions)  # a conjunction looks as far as its parts
    if horizon > task.duration + 1e-9:
        raise ConfigError(
            f"{task.source}: the spec {task.spec.name} looks {horizon:g} s ahead but rollouts last "
            f"{task.duration:g} s ('duration'); lengthen the rollouts or shorten the spec's windows"
        )
    scene = load_scene(task.scene)
    recorded = set(scene.recorded_signals)
    unknown = sorted(parts.signals - recorded)
    if unknown:
        raise SpecError(
            f"signal {', '.join(unknown)} is not recorded by rollouts in the scene {scene.name} (they record {', '.join(scene.recorded_signals)})",
            str(task.spec),
        )
    behaviour = load_behaviour(task.behaviour) if task.behaviour is not None else None
    backend = new_backend(task.backend, task.command) if execute else None
    return space, SkillObjective(models, space, task, behaviour, scene, parts, backend)


def placement_parts(parts: SpecParts, placements: tuple[dict, ...]) -> Placements:
    """The spec's parts at each placement, named `placement 2 (holder 0.6,0.25,0.04 yaw 0.3): PART`."""
    labels = []
    for index, placement in enumerate(placements):
        poses = ", ".join(f"{name} {','.join(f'{v:g}' for v in pose.position)} yaw {pose.yaw:g}" for name, pose in placement.items())
        labels.append(f"placement {index + 1} ({poses})")
    return Placements(tuple(f"{label}: {part}" for label in labels for part in parts.names), parts.semantics, len(labels))


def prepare_objective(task: Task, models: dict[str, HSMM], spec: ast.Spec | None = None) -> tuple[SearchSpace, SkillObjective, Outcome, Summary]:
    """`objective_for`, then the unoptimised skill executed once: the space, the objective (which
    the caller closes), the unoptimised outcome and the summary of a run with no trial yet."""
    space, objective = objective_for(task, models, spec)
    try:
        start = time.perf_counter()
        initial = objective.evaluate(models)
    except BaseException:
        objective.close()
        raise
    summary = Summary.of(task, space, float(initial.robustness), [], time.perf_counter() - start, initial.components)
    return space, objective, initial, summary


def start_run(
    task: Task,
    out: Path,
    learn_progress: Callable[[str], None] = lambda message: None,
    inputs: dict[str, Any] | None = None,
    models: dict[str, HSMM] | None = None,
    spec: ast.Spec | None = None,
    files: Mapping[str, str] | None = None,
) -> PreparedRun:
    """Check `out`, learn or load the model, check the spec, execute the unoptimised skill, then
    create the run directory with all of that in it. `inputs` is the record of the task file and
    command-line overrides (`resume.inputs_record`; default: `task` as its own file).

    From Python objects: `models` instead of the task's, `spec` instead of reading `task.spec`,
    and `files` (name -> text) written into the run directory with the rest, for task paths
    that point into it."""
    check_new_run_path(Path(out))
    if models is None:
        if task.model is None:
            learn_progress(f"learning the skills of {task.source.name}")
        models = task_models(task)
    space, objective = objective_for(task, models, spec)
    try:
        with StagedRun(out) as staged:
            for name, text in (files or {}).items():
                write_atomically(staged.path / name, text)
            objective.exchange_in(staged.path)  # the unoptimised skill's execution is part of the new run
            start = time.perf_counter()
            initial = objective.evaluate(models, trial=0)
            summary = Summary.of(task, space, float(initial.robustness), [], time.perf_counter() - start, initial.components)
            run = staged.commit(task, models, initial.payload, summary, inputs if inputs is not None else inputs_record(task, {}, task, spec))
        objective.exchange_in(run.path)
    except BaseException:
        objective.close()
        raise
    return PreparedRun(task, run, models, space, objective, [], summary, initial.payload)


def resume_run(out: Path, trials: int | None = None, file_task: Task | None = None, given: dict[str, Any] | None = None) -> PreparedRun:
    """Reopen a run directory to finish it (or extend it to `trials` in total), holding its
    write lock. With `file_task` (the task file named on the command line) and `given` (the
    options given again), refuse when they ask for another run than the recorded one."""
    run = RunDirectory.open(out, for_writing=True)
    try:
        return _reopen(run, out, trials, file_task, given or {})
    except BaseException:
        run.close()
        raise


def _reopen(run: RunDirectory, out: Path, trials: int | None, file_task: Task | None, given: dict[str, Any]) -> PreparedRun:
    task = run.task()
    if file_task is not None:
        check_resume(Path(out), task, run.inputs(), file_task, given)
    if trials is not None:
        task = task.with_overrides(trials=trials)
    pending = run.pending()
    if pending is not None:
        raise RunError(f"{out}: trial {pending.trial} was handed out by stlopt ask and is not told yet; tell its signals first (stlopt tell {out} SIGNALS.csv)")
    return prepared_from(run, task)


def prepared_from(run: RunDirectory, task: Task, execute: bool = True) -> PreparedRun:
    """An existing run ready for more trials: its models, space, objective (executing in the
    run's folder, or only scoring unless `execute`), checked history and summary."""
    models = run.models()
    space, objective = objective_for(task, models, execute=execute)
    objective.exchange_in(run.path)
    history = run.trials()
    if any(len(trial.x) != space.dimension for trial in history):
        raise RunError(f"{run.path / 'trials.jsonl'}: damaged (the recorded points do not have the task's {space.dimension} parameters)")
    return PreparedRun(task, run, models, space, objective, history, run.summary())


class Recorder:
    """Records each finished trial of a run: its line and signals, the best models when it
    improves on the best so far, and the summary."""

    def __init__(self, prepared: PreparedRun) -> None:
        self.prepared = prepared
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
        return Summary.of(prepared.task, prepared.space, initial.initial_robustness, self.history, self.wall_seconds, initial.initial_components)


def optimise(prepared: PreparedRun, on_trial: Callable[[Trial, Trial | None], None] = lambda trial, best: None) -> Summary:
    """Run the remaining trials, recording each; returns the final summary."""
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

    workers = prepared.task.optimizer.workers
    pool = None
    if workers > 1:
        from stl_lfd.optim.workers import WorkerPool

        pool = WorkerPool(prepared.task, prepared.models, getattr(prepared.run, "path", None), workers)
    try:
        run_trials(
            objective,
            prepared.space.bounds,
            prepared.task.optimizer,
            prepared.history,
            record,
            prepared.objective.composition,
            pool,
            prepared.features(),
            prepared.plan(),
        )
    except BaseException:
        if pool is not None:
            pool.stop()  # now: the trials in flight are lost, as with one worker
        raise
    if pool is not None:
        pool.close()
    recorder.wall_seconds += time.perf_counter() - mark
    summary = recorder.summary()
    prepared.run.write_summary(summary)
    return summary
