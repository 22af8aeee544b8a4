"""Which skill `stlopt replay` executes: a model file, a behaviour file, or a trial of a run
directory (which also names the spec, scene, duration, semantics and object placements of the
run; a run with several placements is replayed at its first, or at the one given)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from stl_lfd.choices import DEFAULT_SEMANTICS
from stl_lfd.errors import ConfigError, ExecutionError, RunError
from stl_lfd.hsmm import HSMM
from stl_lfd.optim.runs.directory import RunDirectory
from stl_lfd.optim.space import build_search_space
from stl_lfd.optim.task import Task
from stl_lfd.optim.trials import best_trial
from stl_lfd.sim.registry import backend_class
from stl_lfd.skill.behaviour import load_skill
from stl_lfd.skill.replay import ReplaySkill, filming_backend
from stl_lfd.spelling import spelled


@dataclass(frozen=True)
class ReplayRequest:
    """What to replay; None fields take the run's settings or the defaults."""

    source: Path
    trial: str = "best"
    spec: Path | None = None
    scene: str | None = None
    duration: float | None = None
    semantics: str | None = None
    place: tuple[str, ...] = ()  # NAME=x,y[,z[,yaw]] texts for the scene's object frames
    backend: str | None = None  # a backend that films (default: the run's, if it does; else DEFAULT_BACKEND)


def resolve_skill(request: ReplayRequest) -> ReplaySkill:
    """The models and settings named by a replay request."""
    source = request.source
    if source.is_dir():
        run = trial_skill(source, request.trial)
        task = run.task
        return ReplaySkill(
            models=run.models,
            behaviour=task.behaviour,
            spec=request.spec or task.spec,
            scene=request.scene or task.scene,
            duration=request.duration or task.duration,
            semantics=request.semantics or task.semantics,
            nu=task.nu,
            default_video=source / f"replay-trial-{run.trial}.mp4",
            placement=request.place or (task.placements[0] if task.placements else ()),
            backend=filming_backend(request.backend or (task.backend if backend_class(task.backend).capabilities.films else None)),
        )
    if not source.exists():
        raise ConfigError(f"{source}: no such model file, behaviour file or run directory")
    if request.trial != "best":
        raise ExecutionError(f"{spelled('trial')} applies to run directories, not to a model or behaviour file")
    models, behaviour = load_skill(source)
    return ReplaySkill(
        models=models,
        behaviour=source if behaviour is not None else None,
        spec=request.spec,
        scene=request.scene or (behaviour.scene if behaviour is not None else "free_space"),
        duration=request.duration,
        semantics=request.semantics or DEFAULT_SEMANTICS,
        nu=1.0,
        default_video=Path("replay.mp4"),
        placement=request.place,
        backend=filming_backend(request.backend),
    )


@dataclass(frozen=True)
class TrialSkill:
    """The models of one trial of a run (0: the unoptimised skill), and the run's task (its
    spec, scene, duration, semantics and placements), for `stlopt replay`."""

    trial: int
    models: dict[str, HSMM]
    task: Task


def trial_skill(path: Path, which: str = "best") -> TrialSkill:
    """The model of trial `which` (`best`, `initial`/`0`, or a trial number) of a run."""
    run = RunDirectory.open(path)
    task, models, trials = run.task(), run.models(), run.trials()
    if which == "best":
        best = best_trial(trials)
        number = best.trial if best is not None else 0
        if number == 0:
            raise RunError(f"{path}: the run has no successful trial yet; replay the unoptimised skill with {spelled('trial')} initial")
    elif which == "initial":
        number = 0
    else:
        number = _trial_number(which, len(trials), path)
    if number > 0:
        found = [trial for trial in trials if trial.trial == number]
        models = build_search_space(models, task.parameters, task.source).apply(models, found[0].x)
    return TrialSkill(number, models, task)


def _trial_number(which: str, finished: int, path: Path) -> int:
    """`--trial` as a number from 1 to the run's finished trials."""
    try:
        number = int(which)
    except ValueError:
        raise ConfigError(f"{spelled('trial')} must be 'best', 'initial' or a trial number (got {which!r})") from None
    if not 1 <= number <= finished:
        have = f"trials 1 to {finished}" if finished else "no finished trials"
        raise RunError(f"{path}: no trial {number} (the run has {have}; 'initial' is the unoptimised skill)")
    return number
