"""`stlopt replay`: execute a skill again in a simulator, in its GUI or into a video.

The skill comes from a model file, a behaviour file, or a trial of a run directory (which
also names the spec, scene, duration, semantics and object placements of the run; a run with
several placements is replayed at its first, or at the one given with `--place`).
"""

from __future__ import annotations

from contextlib import AbstractContextManager
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from stl_lfd.errors import ConfigError, ExecutionError
from stl_lfd.files import atomic_output, check_output_file
from stl_lfd.hsmm import HSMM
from stl_lfd.poses import Pose
from stl_lfd.sim import DEFAULT_RATE, BackendOptions, new_backend
from stl_lfd.sim.registry import DEFAULT_BACKEND, backend_class, backend_names
from stl_lfd.skill.behaviour import load_behaviour, load_skill
from stl_lfd.skill.execution import scene_with_spec_regions
from stl_lfd.skill.placed import PlacedSkill, placed_scene
from stl_lfd.stl.evaluate import evaluate_table

ProgressFactory = Callable[[str, int], AbstractContextManager[Callable[[int], None]]]


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


@dataclass(frozen=True)
class Skill:
    """Models to execute (one skill, or the skills of a behaviour) with the settings they are
    judged under."""

    models: dict[str, HSMM]
    behaviour: Path | None
    spec: Path | None
    scene: str
    duration: float | None
    semantics: str
    nu: float
    default_video: Path
    placements: tuple[dict[str, Pose], ...] = ()
    backend: str = DEFAULT_BACKEND


@dataclass(frozen=True)
class ReplayOutcome:
    robustness: float | None
    semantics: str
    spec: Path | None
    video: Path | None
    frames: int


def replay_skill(request: ReplayRequest, gui: bool, video: Path | None, progress: ProgressFactory) -> ReplayOutcome:
    """Execute the requested skill in the GUI (real time) or headless into a video."""
    skill = resolve_skill(request)
    if not gui:
        from stl_lfd.sim.video import VIDEO_SUFFIXES

        video = check_output_file(video if video is not None else skill.default_video, VIDEO_SUFFIXES, "video")
    scene = scene_with_spec_regions(skill.scene, skill.spec)
    placement = request.place if request.place else (skill.placements[0] if skill.placements else {})
    behaviour = load_behaviour(skill.behaviour) if skill.behaviour is not None else None
    placed = PlacedSkill(skill.models, behaviour, placed_scene(scene, placement), skill.duration)
    if gui:
        from stl_lfd.sim.video import pace_real_time

        with new_backend(skill.backend, BackendOptions(gui=True)) as backend:
            rollout = placed.execute(backend, DEFAULT_RATE, pace_real_time())
        written, frames = None, 0
    else:
        written = video
        rollout, frames = _film(placed, skill.backend, written, progress)
    robustness = None
    if skill.spec is not None:
        robustness = evaluate_table(skill.spec, rollout.signals, skill.semantics, skill.nu).robustness
    return ReplayOutcome(robustness, skill.semantics, skill.spec, written, frames)


def _film(placed: PlacedSkill, backend_name: str, path: Path, progress: ProgressFactory):
    """Execute while filming into `path`; the file appears only once it is complete."""
    from stl_lfd.sim.video import VideoRecorder, frame_count

    reference, camera = placed.reference(), placed.scene.camera
    with new_backend(backend_name) as backend:
        with atomic_output(path) as partial, progress(f"filming {path.name}", frame_count(reference.duration, camera.fps)) as advance:
            recorder = VideoRecorder(partial, camera, advance)
            try:
                rollout = placed.execute(backend, DEFAULT_RATE, recorder, reference)
            finally:
                recorder.close()
    return rollout, recorder.frames


def resolve_skill(request: ReplayRequest) -> Skill:
    """The model and settings named by a replay request."""
    source = request.source
    if source.is_dir():
        from stl_lfd.optim.runs.directory import trial_skill

        run = trial_skill(source, request.trial)
        task = run.task
        return Skill(
            models=run.models,
            behaviour=task.behaviour,
            spec=request.spec or task.spec,
            scene=request.scene or task.scene,
            duration=request.duration or task.duration,
            semantics=request.semantics or task.semantics,
            nu=task.nu,
            default_video=source / f"replay-trial-{run.trial}.mp4",
            placements=task.placements,
            backend=filming_backend(request.backend or (task.backend if backend_class(task.backend).capabilities.films else None)),
        )
    if not source.exists():
        raise ConfigError(f"{source}: no such model file, behaviour file or run directory")
    if request.trial != "best":
        raise ExecutionError("--trial applies to run directories, not to a model or behaviour file")
    models, behaviour = load_skill(source)
    return Skill(
        models=models,
        behaviour=source if behaviour is not None else None,
        spec=request.spec,
        scene=request.scene or (behaviour.scene if behaviour is not None else "free_space"),
        duration=request.duration,
        semantics=request.semantics or "new",
        nu=1.0,
        default_video=Path("replay.mp4"),
        backend=filming_backend(request.backend),
    )


def filming_backend(name: str | None) -> str:
    """`name` (default: `DEFAULT_BACKEND`), checked to be a backend that films."""
    name = name or DEFAULT_BACKEND
    if not backend_class(name).capabilities.films:
        filming = [other for other in backend_names() if backend_class(other).capabilities.films]
        raise ConfigError(f"the {name} backend cannot replay a skill to watch (choose from {', '.join(filming)})")
    return name
