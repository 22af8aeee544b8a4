"""Running one skill model: its reference (`stl_lfd.skill.reference`), executed in a scene."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from stl_lfd.hsmm import HSMM
from stl_lfd.sim import DEFAULT_RATE, Backend, Rollout, Scene, execute, load_scene
from stl_lfd.skill.reference import build_reference


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
    return execute(build_reference({"skill": model}, duration=duration, poses=scene.frame_poses), scene, backend, rate, observer)


def scene_with_spec_regions(scene_name: str, spec_path: str | Path | None) -> Scene:
    """The scene, with the region definitions of the spec (if any) drawn as boxes."""
    scene = load_scene(scene_name)
    if spec_path is None:
        return scene
    from stl_lfd.stl import load_spec
    from stl_lfd.stl.regions import region_boxes

    return scene.with_regions(region_boxes(load_spec(spec_path)))
