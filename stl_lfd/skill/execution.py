"""Running a skill model: retrieval of its reference, then execution in a scene.

The glue between `stl_lfd.hsmm` and `stl_lfd.sim`, shared by `rollout`, `replay` and the
optimiser, so that every command executes a model the same way.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from stl_lfd.errors import ModelError
from stl_lfd.hsmm import HSMM, retrieve
from stl_lfd.sim import DEFAULT_RATE, SIMULATION_RATE, Backend, Reference, Rollout, Scene, execute, load_scene

POSITION_SIGNALS = ("x", "y", "z")


def reference_of(model: HSMM, duration: float | None = None, name: str = "skill") -> Reference:
    """The model's retrieved trajectory at the simulation rate, as a reference to execute; its
    samples are labelled with the skill's `name` and the (1-based) HSMM state they follow."""
    missing = [name for name in POSITION_SIGNALS if name not in model.signal_names_]
    if missing:
        raise ModelError(f"the model has no signal {', '.join(missing)}: only position skills (x, y, z) can be executed")
    trajectory = retrieve(model, duration, rate=SIMULATION_RATE)
    columns = [model.signal_names_.index(name) for name in POSITION_SIGNALS]
    gripper = trajectory.positions[:, model.signal_names_.index("gripper")] if "gripper" in model.signal_names_ else None
    skills = np.full(trajectory.times.shape, name)
    return Reference(trajectory.times, trajectory.positions[:, columns], gripper, skills=skills, states=trajectory.states + 1)


def rollout_model(
    model: HSMM,
    scene: Scene,
    backend: str | Backend = "pybullet",
    duration: float | None = None,
    rate: float = DEFAULT_RATE,
    observer: Callable | None = None,
) -> Rollout:
    """Retrieve and execute `model` for `duration` seconds (default: its expected duration)."""
    return execute(reference_of(model, duration), scene, backend, rate, observer)


def scene_with_spec_regions(scene_name: str, spec_path: str | Path | None) -> Scene:
    """The scene, with the region definitions of the spec (if any) drawn as boxes."""
    scene = load_scene(scene_name)
    if spec_path is None:
        return scene
    from stl_lfd.stl import load_spec
    from stl_lfd.stl.regions import region_boxes

    return scene.with_regions(region_boxes(load_spec(spec_path)))
