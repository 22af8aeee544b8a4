"""`optimize`: the optimisation from Python objects, kept in memory.

    from stl_lfd import HSMM, Spec, optimize, Parameters, MeanParameters, Optimizer

    result = optimize(model, Spec.load("specs/phi1.stl"), Parameters(means=MeanParameters((2, 3))),
                      Optimizer(trials=16), duration=22, backend="kinematic")
    result.best_robustness, result.best_model

The same seed gives the same trials as `stlopt optimize` on a task file with the same settings.
With `out=`, the run is also recorded in a run directory, as `stlopt optimize` records it: the
spec (`spec.stl`) and the unoptimised skill are written into it, so that `stlopt report OUT`
reads it and `stlopt optimize OUT/task.yaml --out OUT --resume -N MORE` continues it.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Callable, Mapping, Sequence

from stl_lfd.choices import DEFAULT_SEMANTICS
from stl_lfd.errors import ConfigError
from stl_lfd.hsmm import HSMM
from stl_lfd.limits import samples_problem
from stl_lfd.optim.inputs import resolve
from stl_lfd.optim.runs.directory import MODEL_FILE, TASK_FILE
from stl_lfd.optim.runs.prepare import PreparedRun, prepare_objective, start_run
from stl_lfd.optim.runs.recorder import finish_run
from stl_lfd.optim.runs.store import MemoryRun, RecordedRun
from stl_lfd.optim.settings import SINGLE_SKILL, Optimizer, Parameters
from stl_lfd.optim.summary import Summary
from stl_lfd.optim.task import Task
from stl_lfd.optim.trials import Trial, best_trial
from stl_lfd.poses import Pose
from stl_lfd.signals import SignalTable
from stl_lfd.sim import Command
from stl_lfd.sim.registry import DEFAULT_BACKEND
from stl_lfd.stl import Spec, format_spec

SPEC_FILE = "spec.stl"  # the spec of a run started from Python, written into its directory


@dataclass
class Result:
    """What an optimisation found.

    Attributes:
        best_models: skill name -> adapted model of the best trial (`skill` for one skill); the
            unoptimised models when no trial succeeded.
        history: every trial in order.
        summary: the run's `Summary` (what `summary.json` holds).
        signals: trial number -> recorded signals (0 is the unoptimised skill).
    """

    best_models: dict[str, HSMM]
    history: list[Trial]
    summary: Summary
    signals: dict[int, SignalTable] = field(default_factory=dict, repr=False)

    @property
    def best_model(self) -> HSMM:
        """The adapted model of a single-skill optimisation."""
        if SINGLE_SKILL not in self.best_models:
            raise ConfigError(f"several skills were optimised ({', '.join(self.best_models)}): use best_models")
        return self.best_models[SINGLE_SKILL]

    @property
    def best_trial(self) -> Trial | None:
        """The trial of highest robustness, None when every trial failed."""
        return best_trial(self.history)

    @property
    def best_robustness(self) -> float | None:
        return self.summary.best_robustness

    @property
    def initial_robustness(self) -> float:
        """Robustness of the unoptimised skill."""
        return self.summary.initial_robustness

    @property
    def satisfied(self) -> bool:
        return self.summary.satisfied


def optimize(
    models: HSMM | dict[str, HSMM],
    spec: Spec | str | Path,
    parameters: Parameters | dict[str, Parameters],
    optimizer: Optimizer | None = None,
    *,
    duration: float,
    scene: str = "free_space",
    backend: str = DEFAULT_BACKEND,
    semantics: str = DEFAULT_SEMANTICS,
    nu: float = 1.0,
    rate: float = 100.0,
    behaviour: str | Path | None = None,
    command: Command | None = None,
    placements: Sequence[Mapping[str, Pose]] = (),
    on_trial: Callable[[Trial, Trial | None], None] = lambda trial, best: None,
    out: str | Path | None = None,
) -> Result:
    """Adapt `models` so that their execution satisfies `spec`, as robustly as possible.

    Args:
        models: the skill, or skill name -> model for a `behaviour` of several skills.
        spec: a `Spec`, STL text, or the path of a `.stl` file.
        parameters: what moves (means, durations, transitions) and its bounds; per skill name
            for a behaviour.
        optimizer: method, initial (M) and total (N) trials, seed (default `Optimizer()`).
        duration: seconds of each rollout (the spec's windows must fit in it).
        command: the executor of `backend="command"` (its exchange files go to a temporary
            folder per execution, removed afterwards).
        placements: where the scene's object frames stand (frame name -> `Pose`); several
            make every trial execute once per placement and score the worst.
        on_trial: called after each trial with it and the best trial so far.
        out: a new run directory to record the run in as well (default: memory only).

    Returns:
        the best models and robustness, the history of trials and the summary.
    """
    spec = spec if isinstance(spec, Spec) else Spec.load(spec) if isinstance(spec, Path) else Spec.parse(spec)
    models = models if isinstance(models, dict) else {SINGLE_SKILL: models}
    parameters = parameters if isinstance(parameters, dict) else {SINGLE_SKILL: parameters}
    problem = samples_problem(duration, rate)
    if problem:
        raise ConfigError(f"duration and rate: {problem}")
    task = Task(
        name="python", spec=Path(spec.source), model=None, demos=None, behaviour=Path(behaviour) if behaviour is not None else None, states=0,
        scene=scene, backend=backend, semantics=semantics, nu=nu, duration=float(duration), rate=float(rate),
        parameters=parameters, optimizer=optimizer or Optimizer(), source=Path("<python>"), command=command,
        placements=tuple(dict(placement) for placement in placements),
    )  # fmt: skip
    if out is None:
        resolved = resolve(task, spec.tree)
        space, objective, initial, summary = prepare_objective(resolved, models)
        prepared = PreparedRun(resolved, MemoryRun(initial.payload), models, space, objective, [], summary)
    else:
        prepared = _start_recorded_run(task, models, spec, Path(out))
    with prepared:
        summary = finish_run(prepared, on_trial)
    record = prepared.run
    return Result(record.best_models or models, record.trials, summary, record.signals)


def _start_recorded_run(task: Task, models: dict[str, HSMM], spec: Spec, out: Path) -> PreparedRun:
    """`start_run` for a task built from objects: its spec and models are written into `out`,
    and its task file is `out/task.yaml`, so that the run reads like one of `stlopt optimize`."""
    folder = out.resolve()
    task = replace(task, name=folder.name, spec=folder / SPEC_FILE, model=folder / MODEL_FILE if task.behaviour is None else None, source=folder / TASK_FILE)
    prepared = start_run(task, out, models=models, spec=spec.tree, files={SPEC_FILE: format_spec(spec.tree)})
    prepared.run = RecordedRun(prepared.initial_signals, prepared.run)
    return prepared
