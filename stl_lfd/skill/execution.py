"""Running one skill model: its reference (`stl_lfd.skill.reference`), executed in a scene;
and skills placed in a scene executed once on a backend of their own (`stlopt rollout`)."""

from __future__ import annotations

import time
from contextlib import AbstractContextManager
from pathlib import Path
from typing import Callable

from stl_lfd.hsmm import HSMM
from stl_lfd.sim import DEFAULT_RATE, Backend, BackendOptions, Command, Reference, Rollout, Scene, execute, load_scene, new_backend
from stl_lfd.sim.registry import check_command_for
from stl_lfd.skill.placed import PlacedSkill
from stl_lfd.skill.reference import build_reference

# `progress(description, total)`: a context manager yielding a function of the steps done.
ProgressFactory = Callable[[str, int], AbstractContextManager[Callable[[int], None]]]
LONG_ROLLOUT_SECONDS = 120.0  # simulated seconds from which a rollout reports its progress


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


def timed_rollout(
    skill: PlacedSkill,
    backend: str,
    rate: float = DEFAULT_RATE,
    command: Command | None = None,
    reference: Reference | None = None,
    progress: ProgressFactory | None = None,
) -> tuple[Rollout, str]:
    """Execute `skill` (or its `reference`, if already retrieved) once on a new `backend`,
    recording at `rate` samples per second; `command`: the executor of the command backend.
    A simulation longer than `LONG_ROLLOUT_SECONDS` reports each simulated second to `progress`.

    Returns:
        the rollout, and how it went in one phrase (`Capabilities.describe_rollout`).
    """
    check_command_for(backend, command)
    reference = skill.reference() if reference is None else reference
    with new_backend(backend, BackendOptions(command=command)) as runner:
        capabilities = runner.capabilities
        start = time.perf_counter()
        if progress is not None and capabilities.simulates and reference.duration > LONG_ROLLOUT_SECONDS:
            with progress(f"simulating {reference.duration:.0f} s", int(reference.duration)) as advance:
                result = skill.execute(runner, rate, whole_seconds(advance), reference)
        else:
            result = skill.execute(runner, rate, reference=reference)
        elapsed = time.perf_counter() - start
    return result, capabilities.describe_rollout(result.signals.duration, elapsed, result.tracking_rms, result.tracking_max)


def whole_seconds(advance: Callable[[int], None]) -> Callable[[float, object], None]:
    """A simulation observer that reports progress once per simulated second."""
    shown = [-1]

    def observe(time: float, world: object) -> None:
        if int(time) != shown[0]:
            shown[0] = int(time)
            advance(shown[0])

    return observe
