"""Execution backends, found by name.

    with new_backend("mujoco") as backend:             # one world per scene, kept until closed
        rollout = execute(reference, scene, backend)

| name        | class                                   | what it does                                   |
|-------------|-----------------------------------------|------------------------------------------------|
| `pybullet`  | `pybullet_panda.PyBulletBackend`        | a compliant Panda simulated in PyBullet        |
| `mujoco`    | `mujoco_panda.MujocoBackend`            | a compliant Panda simulated in MuJoCo          |
| `kinematic` | `kinematic.KinematicBackend`            | the reference itself, recorded as is           |
| `command`   | `command.CommandBackend`                | an external program (a real robot)             |

A new backend is a class following `backend.Backend` (`backend.BackendBase` gives the common
parts) and one line in `REGISTRY` (or `register(name, target, summary)` from outside the package).
Classes are imported on first use: naming the backends, as the command line does for its
choices, loads no simulator.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from stl_lfd.errors import ConfigError, ExecutionError
from stl_lfd.lazy import loaded
from stl_lfd.spelling import spelled

if TYPE_CHECKING:
    from stl_lfd.sim.backend import Backend, BackendOptions
    from stl_lfd.sim.executor import Command


@dataclass
class Entry:
    """A registered backend: its class, or `module:Class` until first used, and one line for
    humans."""

    target: "str | type[Backend]"
    summary: str

    def load(self) -> "type[Backend]":
        self.target = loaded(self.target)
        return self.target


REGISTRY: dict[str, Entry] = {
    "pybullet": Entry("stl_lfd.sim.pybullet_panda:PyBulletBackend", "a compliant Panda simulated in PyBullet"),
    "mujoco": Entry("stl_lfd.sim.mujoco_panda:MujocoBackend", "a compliant Panda simulated in MuJoCo"),
    "kinematic": Entry("stl_lfd.sim.kinematic:KinematicBackend", "records the reference itself"),
    "command": Entry("stl_lfd.sim.command:CommandBackend", "runs an external program"),
}
DEFAULT_BACKEND = "pybullet"


def backend_names() -> tuple[str, ...]:
    """The registered backends' names, in the registry's order."""
    return tuple(REGISTRY)


def backends_help() -> str:
    """One phrase per backend, for `--help`."""
    return "; ".join(f"{name}: {entry.summary}" for name, entry in REGISTRY.items())


def register(name: str, target: "str | type[Backend]", summary: str) -> None:
    """Make a backend class (or its `module:Class`) available by `name` (task files, `--backend`)."""
    REGISTRY[name] = Entry(target, summary)


def backend_class(name: str) -> "type[Backend]":
    """The class registered as `name`; ExecutionError for an unknown name."""
    if name not in REGISTRY:
        raise ExecutionError(f"unknown backend '{name}' (choose from {', '.join(REGISTRY)})")
    return REGISTRY[name].load()


def new_backend(name: str, options: "BackendOptions | None" = None) -> "Backend":
    """A backend of the caller's own, to close when done (backends are context managers).

    The `command` backend needs `options.command` (others ignore it); backends without a GUI
    refuse `options.gui`.
    """
    from stl_lfd.sim.backend import BackendOptions

    options = options or BackendOptions()
    cls = backend_class(name)
    if cls.capabilities.needs_command and options.command is None:
        raise ConfigError(f"the {name} backend needs a command ({spelled('command')}, or 'command' in the task file)")
    if options.gui and not cls.capabilities.has_gui:
        raise ExecutionError(f"the {name} backend has no GUI (choose from {', '.join(gui_backends())}, or record a video)")
    return cls.open(options)


def check_command_for(backend: str, command: "Command | None") -> None:
    """ConfigError when an executor `command` is given for a backend that runs none."""
    if command is not None and not backend_class(backend).capabilities.needs_command:
        raise ConfigError(f"{spelled('command')} is for {spelled('backend')} command (the run's backend is {backend})")


def gui_backends() -> tuple[str, ...]:
    """Backends that can show an execution in a window."""
    return tuple(name for name in REGISTRY if backend_class(name).capabilities.has_gui)


_shared: dict[str, "Backend"] = {}


def get_backend(name: str) -> "Backend":
    """The process-wide backend called `name`, for one-off executions (its worlds are built
    once and kept until the process ends); code that runs many rollouts owns one with
    `new_backend`."""
    if name not in _shared:
        _shared[name] = new_backend(name)
    return _shared[name]
