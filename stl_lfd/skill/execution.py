"""Running a skill model: retrieval of its reference, then execution in a scene.

The glue between `stl_lfd.hsmm` and `stl_lfd.sim`, shared by `rollout`, `replay` and the
optimiser, so that every command executes a model the same way.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, Mapping, Sequence

import numpy as np

from stl_lfd.errors import ConfigError, ModelError
from stl_lfd.hsmm import HSMM, TPHSMM, Trajectory
from stl_lfd.hsmm.retrieval import retrieve_batch
from stl_lfd.poses import BASE_FRAME, Pose
from stl_lfd.sim import DEFAULT_RATE, SIMULATION_RATE, Backend, Reference, Rollout, Scene, execute, load_scene

POSITION_SIGNALS = ("x", "y", "z")


def reference_of(model: HSMM, duration: float | None = None, name: str = "skill", poses: Mapping[str, Pose] | None = None) -> Reference:
    """The model's retrieved trajectory at the simulation rate, as a reference to execute; its
    samples are labelled with the skill's `name` and the (1-based) HSMM state they follow. A
    TP-HSMM is retrieved for its frames at `poses` (frame name -> pose)."""
    return references_of([model], [duration], name, poses)[0]


def references_of(models: Sequence[HSMM], durations: Sequence[float | None], name: str = "skill", poses: Mapping[str, Pose] | None = None) -> list[Reference]:
    """`reference_of` each of N models of the skill `name` (for `durations` seconds each),
    retrieved together (`retrieve_batch`)."""
    for model in models:
        missing = [signal for signal in POSITION_SIGNALS if signal not in model.signal_names_]
        if missing:
            raise ModelError(f"the model has no signal {', '.join(missing)}: only position skills (x, y, z) can be executed")
    frames = {frame: pose for model in models for frame, pose in skill_poses(model, poses or {}, name).items()}
    trajectories = retrieve_batch(models, durations, rate=SIMULATION_RATE, poses=frames)
    return [_reference(model, trajectory, name) for model, trajectory in zip(models, trajectories)]


def _reference(model: HSMM, trajectory: Trajectory, name: str) -> Reference:
    """The reference of a retrieved `trajectory` of `model`, its samples labelled `name`."""
    columns = [model.signal_names_.index(signal) for signal in POSITION_SIGNALS]
    gripper = trajectory.positions[:, model.signal_names_.index("gripper")] if "gripper" in model.signal_names_ else None
    skills = np.full(trajectory.times.shape, name)
    return Reference(
        trajectory.times, trajectory.positions[:, columns], gripper, skills=skills, states=trajectory.states + 1, orientations=trajectory.orientations
    )


def skill_poses(model: HSMM, poses: Mapping[str, Pose], name: str = "skill") -> dict[str, Pose]:
    """The poses of the frames of `model` (none for a plain HSMM), from `poses`; ConfigError
    naming the frames the scene lacks."""
    if not isinstance(model, TPHSMM):
        return {}
    missing = [frame for frame in model.frame_names_ if frame != BASE_FRAME and frame not in poses]
    if missing:
        known = ", ".join(poses) or "none"
        raise ConfigError(f"the {name} model is learned in frame {', '.join(missing)}, which the scene does not have (its frames: {known})")
    return {frame: poses[frame] for frame in model.frame_names_ if frame != BASE_FRAME}


def rollout_model(
    model: HSMM,
    scene: Scene,
    backend: str | Backend = "",
    duration: float | None = None,
    rate: float = DEFAULT_RATE,
    observer: Callable | None = None,
) -> Rollout:
    """Retrieve and execute `model` for `duration` seconds (default: its expected duration),
    a TP-HSMM for the poses of the scene's frames of the same names."""
    return execute(reference_of(model, duration, poses=scene.frame_poses), scene, backend, rate, observer)


def scene_with_spec_regions(scene_name: str, spec_path: str | Path | None) -> Scene:
    """The scene, with the region definitions of the spec (if any) drawn as boxes."""
    scene = load_scene(scene_name)
    if spec_path is None:
        return scene
    from stl_lfd.stl import load_spec
    from stl_lfd.stl.regions import region_boxes

    return scene.with_regions(region_boxes(load_spec(spec_path)))
