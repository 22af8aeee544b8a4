"""An optimisation run from a task file: prepare (model, space, objective, initial skill), then
the trial loop, recording everything in the run directory as it goes."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from stl_lfd.errors import ConfigError, SpecError
from stl_lfd.execution import rollout_model
from stl_lfd.hsmm import HSMM, learn_from_folder, load_model
from stl_lfd.optim.loop import Outcome, Trial, best_trial, run_trials
from stl_lfd.optim.rundir import RunDirectory
from stl_lfd.optim.space import ParameterSpace, build_space
from stl_lfd.optim.task import Task
from stl_lfd.sim import Scene, load_scene
from stl_lfd.stl import Robustness, compile_spec, load_spec


class SkillObjective:
    """x -> adapted model -> rollout -> robustness of the recorded signals (payload: signals)."""

    def __init__(self, model: HSMM, space: ParameterSpace, task: Task, scene: Scene, robustness: Robustness) -> None:
        self.model, self.space, self.task, self.scene, self.robustness = model, space, task, scene, robustness

    def __call__(self, x: np.ndarray) -> Outcome:
        return self.evaluate(self.space.apply(self.model, x))

    def evaluate(self, model: HSMM) -> Outcome:
        rollout = rollout_model(model, self.scene, self.task.backend, self.task.duration, self.task.rate)
        signals = rollout.signals
        return Outcome(self.robustness(signals.columns, signals.times), signals)


@dataclass
class PreparedRun:
    task: Task
    run: RunDirectory
    model: HSMM
    space: ParameterSpace
    objective: SkillObjective
    history: list[Trial]
    summary: dict[str, Any]


def objective_for(task: Task, model: HSMM) -> tuple[ParameterSpace, SkillObjective]:
    """The parameter space and the objective of `task`; spec problems are found here, before
    any trial: unknown signals, and windows that reach past the rollout duration."""
    space = build_space(model, task.parameters, task.source)
    robustness = compile_spec(load_spec(task.spec), task.semantics, task.nu, source=str(task.spec))
    if robustness.horizon > task.duration + 1e-9:
        raise ConfigError(
            f"{task.source}: the spec {task.spec.name} looks {robustness.horizon:g} s ahead but rollouts last "
            f"{task.duration:g} s ('duration'); lengthen the rollouts or shorten the spec's windows"
        )
    recorded = {"x", "y", "z", "gripper", "force"}
    unknown = sorted(set(robustness.signals) - recorded)
    if unknown:
        raise SpecError(f"{task.spec}: signal {', '.join(unknown)} is not recorded by rollouts (they record {', '.join(sorted(recorded))})")
    return space, SkillObjective(model, space, task, load_scene(task.scene), robustness)


def start_run(task: Task, out: Path, learn_progress: Callable[[str], None] = lambda message: None) -> PreparedRun:
    """Learn or load the model, check the spec, execute the unoptimised skill, then create the
    run directory with all of that in it."""
    if task.demos is not None:
        learn_progress(f"learning K = {task.states} from {task.demos}")
        model, _ = learn_from_folder(task.demos, task.states)
    else:
        model = load_model(task.model)
    space, objective = objective_for(task, model)
    start = time.perf_counter()
    initial = objective.evaluate(model)
    summary = _summary(task, space, float(initial.robustness), [], time.perf_counter() - start)
    run = RunDirectory.create(out, task, model, initial.payload, summary)
    return PreparedRun(task, run, model, space, objective, [], summary)


def resume_run(out: Path, trials: int | None = None) -> PreparedRun:
    """Reopen a run directory to finish it (or extend it to `trials` in total)."""
    run = RunDirectory.open(out)
    task = run.task()
    if trials is not None:
        task = task.with_overrides(trials=trials)
    model = run.model()
    space, objective = objective_for(task, model)
    history = run.trials()
    if any(len(trial.x) != space.dimension for trial in history):
        raise ConfigError(f"{out}: the recorded trials do not match the task's {space.dimension} parameters")
    summary = run.summary()
    return PreparedRun(task, run, model, space, objective, history, summary)


def optimise(prepared: PreparedRun, on_trial: Callable[[Trial, Trial | None], None] = lambda trial, best: None) -> dict[str, Any]:
    """Run the remaining trials, recording each; returns the final summary."""
    run, space, task = prepared.run, prepared.space, prepared.task
    previous_seconds = float(prepared.summary.get("wall_seconds", 0.0))
    initial_robustness = prepared.summary["initial_robustness"]
    start = time.perf_counter()
    best = best_trial(prepared.history)

    def record(trial: Trial, signals: Any) -> None:
        nonlocal best
        trial.parameters = space.as_dict(trial.x)
        run.append_trial(trial, signals)
        improved = trial.robustness is not None and (best is None or trial.robustness > best.robustness)
        if improved:
            best = trial
            run.write_best_model(space.apply(prepared.model, trial.x))
        history.append(trial)
        run.write_summary(_summary(task, space, initial_robustness, history, previous_seconds + time.perf_counter() - start))
        on_trial(trial, best)

    history = list(prepared.history)
    if best is not None and not (run.path / "best_model.npz").exists():
        run.write_best_model(space.apply(prepared.model, best.x))
    run_trials(prepared.objective, space.bounds, task.optimizer, prepared.history, record)
    summary = _summary(task, space, initial_robustness, history, previous_seconds + time.perf_counter() - start)
    run.write_summary(summary)
    return summary


def _summary(task: Task, space: ParameterSpace, initial_robustness: float, history: list[Trial], wall_seconds: float) -> dict[str, Any]:
    best = best_trial(history)
    satisfied = [trial.trial for trial in history if trial.satisfied]
    return {
        "name": task.name,
        "spec": str(task.spec),
        "semantics": task.semantics,
        "nu": task.nu if task.semantics == "new" else None,
        "backend": task.backend,
        "method": task.optimizer.method,
        "seed": task.optimizer.seed,
        "initial_trials": task.optimizer.initial,
        "budget": task.optimizer.trials,
        "initial_robustness": initial_robustness,
        "best_robustness": best.robustness if best else None,
        "best_trial": best.trial if best else None,
        "satisfied": bool(best and best.satisfied),
        "first_satisfied_trial": satisfied[0] if satisfied else None,
        "trials": len(history),
        "failed_trials": sum(trial.status == "failed" for trial in history),
        "complete": len(history) >= task.optimizer.trials,
        "wall_seconds": round(wall_seconds, 3),
        "parameters": list(space.names),
        "best_parameters": space.as_dict(best.x) if best else None,
    }
