"""Executing a skill again in a simulator, in its GUI or into a video (`stlopt replay`): a
`ReplaySkill` (models and the settings they are judged under) in, the execution's robustness
and the video out. Which skill a file or a run's trial names is `optim.runs.replay`'s."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from stl_lfd.errors import ConfigError
from stl_lfd.files import atomic_output, check_output_file
from stl_lfd.hsmm import HSMM
from stl_lfd.poses import Pose
from stl_lfd.sim import DEFAULT_RATE, BackendOptions, new_backend
from stl_lfd.sim.registry import DEFAULT_BACKEND, backend_class, backend_names
from stl_lfd.skill.behaviour import load_behaviour
from stl_lfd.skill.execution import ProgressFactory, scene_with_spec_regions
from stl_lfd.skill.placed import PlacedSkill, placed_scene
from stl_lfd.stl.evaluate import evaluate_table


@dataclass(frozen=True)
class ReplaySkill:
    """Models to execute (one skill, or the skills of a behaviour) with the settings they are
    judged under; `placement`, where the scene's object frames stand (`placed_scene`: poses, or
    NAME=x,y[,z[,yaw]] texts)."""

    models: dict[str, HSMM]
    behaviour: Path | None
    spec: Path | None
    scene: str
    duration: float | None
    semantics: str
    nu: float
    default_video: Path
    placement: dict[str, Pose] | tuple[str, ...] = ()
    backend: str = DEFAULT_BACKEND


@dataclass(frozen=True)
class ReplayOutcome:
    robustness: float | None
    semantics: str
    spec: Path | None
    video: Path | None
    frames: int


def replay_skill(skill: ReplaySkill, gui: bool, video: Path | None, progress: ProgressFactory) -> ReplayOutcome:
    """Execute `skill` in the GUI (real time) or headless into a video (default: its
    `default_video`)."""
    if not gui:
        from stl_lfd.sim.video import VIDEO_SUFFIXES

        video = check_output_file(video if video is not None else skill.default_video, VIDEO_SUFFIXES, "video")
    scene = scene_with_spec_regions(skill.scene, skill.spec)
    behaviour = load_behaviour(skill.behaviour) if skill.behaviour is not None else None
    placed = PlacedSkill(skill.models, behaviour, placed_scene(scene, skill.placement or {}), skill.duration)
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


def filming_backend(name: str | None) -> str:
    """`name` (default: `DEFAULT_BACKEND`), checked to be a backend that films."""
    name = name or DEFAULT_BACKEND
    if not backend_class(name).capabilities.films:
        filming = [other for other in backend_names() if backend_class(other).capabilities.films]
        raise ConfigError(f"the {name} backend cannot replay a skill to watch (choose from {', '.join(filming)})")
    return name
