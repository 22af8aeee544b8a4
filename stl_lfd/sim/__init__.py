"""Execution of reference trajectories: backends, scenes and signal recording.

One interface, `execute(reference, scene, backend)`, returns the recorded signals of the
execution as a `Rollout`. The backends live in a registry (`registry.py`: `pybullet`, `mujoco`,
`kinematic`, `command`), each one class following `backend.Backend` and declaring its
`Capabilities`.

    backend.py, registry.py        the protocol, its capabilities; backends found by name
    steps.py, recorder.py          what a backend observed at each step -> the signal columns
    clearance.py                   the hand's (and two objects') distances, for those columns
    scene.py, scene_file.py        scenes as data; reading scene files and placements
    shapes.py                      the geometry of boxes, cylinders and spheres
    impedance.py                   the compliant controller both simulators use
    pybullet_panda.py              a compliant Panda in PyBullet
    mujoco_panda.py, mujoco_model.py   a compliant Panda in MuJoCo, and its model
    kinematic.py                   the reference itself, executed exactly
    tracking_model.py, grasp_model.py   learned from executions: how a robot tracks a reference,
                                   where a carried object sits in the hand (method plan's)
    command.py, safety.py, plausibility.py   an external executor, behind a safety gate

This package reads no STL and no skill model: callers turn a model into a `Reference` and
pass the regions to draw through `Scene.with_regions`. Names are loaded on first use, so that
naming the backends (the command line's choices) loads no simulator.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from stl_lfd.lazy import lazy_exports

if TYPE_CHECKING:
    from stl_lfd.sim.backend import Backend, Observer
    from stl_lfd.sim.reference import Reference, Rollout
    from stl_lfd.sim.scene import Scene

DEFAULT_RATE = 100.0

_HOMES = {
    "RECORDED_SIGNALS": "stl_lfd.choices",
    "Backend": "stl_lfd.sim.backend",
    "BackendOptions": "stl_lfd.sim.backend",
    "Capabilities": "stl_lfd.sim.backend",
    "DEFAULT_BACKEND": "stl_lfd.sim.registry",
    "backend_class": "stl_lfd.sim.registry",
    "backend_names": "stl_lfd.sim.registry",
    "get_backend": "stl_lfd.sim.registry",
    "new_backend": "stl_lfd.sim.registry",
    "register": "stl_lfd.sim.registry",
    "Command": "stl_lfd.sim.executor",
    "CommandBackend": "stl_lfd.sim.command",
    "exchange_folder": "stl_lfd.sim.command",
    "SIMULATION_RATE": "stl_lfd.sim.reference",
    "TIME_STEP": "stl_lfd.sim.reference",
    "Reference": "stl_lfd.sim.reference",
    "Rollout": "stl_lfd.sim.reference",
    "TrackingWarning": "stl_lfd.sim.reference",
    "read_reference_csv": "stl_lfd.sim.reference",
    "write_reference_csv": "stl_lfd.sim.reference",
    "Safety": "stl_lfd.sim.safety",
    "UnsafeReference": "stl_lfd.sim.safety",
    "check_reference": "stl_lfd.sim.safety",
    "Scene": "stl_lfd.sim.scene",
    "KinematicBackend": "stl_lfd.sim.kinematic",
    "Execution": "stl_lfd.sim.tracking_model",
    "TrackingModel": "stl_lfd.sim.tracking_model",
    "builtin_scenes": "stl_lfd.sim.scene_file",
    "load_scene": "stl_lfd.sim.scene_file",
}
__all__, __getattr__, __dir__ = lazy_exports(__name__, _HOMES, globals())
__all__ += ["DEFAULT_RATE", "execute"]


def execute(reference: "Reference", scene: "Scene", backend: "str | Backend" = "", rate: float = DEFAULT_RATE, observer: "Observer | None" = None) -> "Rollout":
    """Execute `reference` in `scene` and return the signals recorded at `rate` samples/s.

    `backend` is a registered name (default: `DEFAULT_BACKEND`) or a backend object (such as
    one opened with a GUI). Warns (`TrackingWarning`) with the worst error when the robot could
    not follow the reference by more than the scene's tracking tolerance.
    """
    from stl_lfd.sim.reference import warn_if_untracked
    from stl_lfd.sim.registry import DEFAULT_BACKEND, get_backend

    runner = get_backend(backend or DEFAULT_BACKEND) if isinstance(backend, str) else backend
    rollout = runner.run(reference, scene, rate, observer)
    warn_if_untracked(rollout, reference, scene.tracking_tolerance)
    return rollout
