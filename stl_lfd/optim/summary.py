"""`Summary`: what a run found so far, as `summary.json` holds it."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

from stl_lfd.optim.space import SearchSpace
from stl_lfd.optim.task import Task
from stl_lfd.optim.trials import Trial, best_trial


@dataclass(frozen=True)
class Summary:
    """A run's settings and results (the fields of `summary.json`, in its order).

    Attributes:
        initial_robustness: robustness of the unoptimised skill; `initial_components` of its parts.
        best_robustness, best_trial: the best trial so far (None before the first success).
        first_satisfied_trial: the first trial with positive robustness, or None.
        trials, failed_trials: finished trials, and how many of them failed.
        complete: whether the budget (`budget` trials) is spent.
        wall_seconds: time spent by the run, over all its resumptions.
        parameters: the names of the optimised parameters; `best_parameters` their best values.
        executed_by: how the trials were executed: the backend's name, `command: CMD` (an
            executor the run started), or `stlopt ask/tell` (executed elsewhere and told).
    """

    name: str
    spec: str
    semantics: str
    nu: float | None
    backend: str
    method: str
    seed: int
    initial_trials: int
    budget: int
    initial_robustness: float
    initial_components: dict[str, float] | None = None
    best_robustness: float | None = None
    best_trial: int | None = None
    satisfied: bool = False
    first_satisfied_trial: int | None = None
    trials: int = 0
    failed_trials: int = 0
    complete: bool = False
    wall_seconds: float = 0.0
    parameters: tuple[str, ...] = ()
    best_parameters: dict[str, float] | None = None
    executed_by: str = ""

    @classmethod
    def of(
        cls,
        task: Task,
        space: SearchSpace,
        initial_robustness: float,
        history: list[Trial],
        wall_seconds: float,
        initial_components: dict[str, float] | None = None,
        executed_by: str | None = None,
    ) -> "Summary":
        """The summary of `history`, the trials of `task` so far (`executed_by`: default, as the
        task executes them, `execution_of`)."""
        best = best_trial(history)
        satisfied = [trial.trial for trial in history if trial.satisfied]
        return cls(
            name=task.name,
            spec=str(task.spec),
            semantics=task.semantics,
            nu=task.nu if task.semantics == "new" else None,
            backend=task.backend,
            method=task.optimizer.method,
            seed=task.optimizer.seed,
            initial_trials=task.optimizer.initial,
            budget=task.optimizer.trials,
            initial_robustness=initial_robustness,
            initial_components=initial_components,
            best_robustness=best.robustness if best else None,
            best_trial=best.trial if best else None,
            satisfied=bool(best and best.satisfied),
            first_satisfied_trial=satisfied[0] if satisfied else None,
            trials=len(history),
            failed_trials=sum(trial.status == "failed" for trial in history),
            complete=len(history) >= task.optimizer.trials,
            wall_seconds=round(wall_seconds, 3),
            parameters=tuple(space.names),
            best_parameters=space.as_dict(best.x) if best else None,
            executed_by=executed_by or execution_of(task),
        )

    def to_json(self) -> dict[str, Any]:
        data = dataclasses.asdict(self)
        data["parameters"] = list(self.parameters)
        return data

    @classmethod
    def from_json(cls, data: dict[str, Any]) -> "Summary":
        """A summary read back; keys of newer versions are ignored, missing ones take defaults.

        Raises:
            KeyError, TypeError: when a required field is missing or malformed.
        """
        known = {field.name for field in dataclasses.fields(cls)}
        values = {key: value for key, value in data.items() if key in known}
        values["parameters"] = tuple(values.get("parameters", ()))
        return cls(**values)


ASK_TELL = "stlopt ask/tell"


def execution_of(task: Task) -> str:
    """How `task` executes its trials when the run executes them: the backend's name, or
    `command: CMD` for an executor command."""
    if task.backend == "command" and task.command is not None:
        return f"command: {task.command.shown()}"
    return task.backend
