"""Execution of reference trajectories: backends, scenes and signal recording.

One interface, `execute(reference, scene, backend)`, returns the recorded signals of the
execution as a `Rollout`. Backends:

- `kinematic`: the reference itself is the signal (instant, for tests and quick studies);
- `pybullet`: a simulated Franka Panda tracking the reference (see `stl_lfd.sim.panda`);
- `command`: an external program executes it, e.g. on a real robot (see `stl_lfd.sim.command`),
  after the safety gate (`stl_lfd.sim.safety`) has checked it against the scene's limits.

This package reads no STL and no skill model: callers turn a model into a `Reference` and
pass the regions to draw through `Scene.with_regions`.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable, Protocol

from stl_lfd.choices import BACKENDS, RECORDED_SIGNALS
from stl_lfd.errors import ConfigError, ExecutionError
from stl_lfd.sim.command import Command, CommandBackend, exchange_folder
from stl_lfd.sim.kinematic import KinematicBackend
from stl_lfd.sim.reference import (
    SIMULATION_RATE,
    TIME_STEP,
    Reference,
    Rollout,
    TrackingWarning,
    read_reference_csv,
    warn_if_untracked,
    write_reference_csv,
)
from stl_lfd.sim.safety import Safety, UnsafeReference, check_reference
from stl_lfd.sim.scene import Scene, builtin_scenes, load_scene


class Backend(Protocol):
    """What every backend offers."""

    name: str

    def run(self, reference: Reference, scene: Scene, rate: float, observer: Callable | None = None) -> Rollout: ...

    def close(self) -> None: ...

    def __enter__(self) -> "Backend": ...

    def __exit__(self, *exception: object) -> None: ...


DEFAULT_RATE = 100.0

_backends: dict[str, Backend] = {}


def new_backend(name: str, command: Command | None = None, folder: Path | None = None) -> Backend:
    """A backend of the caller's own, to close when done; backends are context managers:

    with new_backend("pybullet") as backend:
        rollout = execute(reference, scene, backend)

    The `command` backend needs its `command`, and writes its exchange folders in `folder` (a
    run directory; default: temporary folders).
    """
    if name not in BACKENDS:
        raise ExecutionError(f"unknown backend '{name}' (choose from {', '.join(BACKENDS)})")
    if name == "command":
        if command is None:
            raise ConfigError("the command backend needs a command (--command, or 'command' in the task file)")
        return CommandBackend(command, folder)
    if name == "kinematic":
        return KinematicBackend()
    from stl_lfd.sim.panda import PyBulletBackend

    return PyBulletBackend()


def get_backend(name: str) -> Backend:
    """The process-wide backend called `name`, for one-off executions (its worlds are built
    once and kept until the process ends); code that runs many rollouts owns one with
    `new_backend`."""
    if name not in _backends:
        _backends[name] = new_backend(name)
    return _backends[name]


def execute(
    reference: Reference,
    scene: Scene,
    backend: str | Backend = "pybullet",
    rate: float = DEFAULT_RATE,
    observer: Callable | None = None,
) -> Rollout:
    """Execute `reference` in `scene` and return the signals recorded at `rate` samples/s.

    `backend` is a name of `BACKENDS` or a backend object (such as a GUI `PyBulletBackend`).

    Warns (`TrackingWarning`) with the worst error when the robot could not follow the
    reference by more than the scene's tracking tolerance.
    """
    runner = get_backend(backend) if isinstance(backend, str) else backend
    rollout = runner.run(reference, scene, rate, observer)
    warn_if_untracked(rollout, reference, scene.tracking_tolerance)
    return rollout


__all__ = [
    "BACKENDS",
    "RECORDED_SIGNALS",
    "SIMULATION_RATE",
    "TIME_STEP",
    "Backend",
    "Command",
    "CommandBackend",
    "DEFAULT_RATE",
    "Reference",
    "Rollout",
    "Safety",
    "Scene",
    "TrackingWarning",
    "UnsafeReference",
    "builtin_scenes",
    "check_reference",
    "exchange_folder",
    "execute",
    "get_backend",
    "new_backend",
    "load_scene",
    "read_reference_csv",
    "write_reference_csv",
]
