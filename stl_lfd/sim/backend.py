"""What an execution backend is: the `Backend` protocol and the capabilities it declares.

A backend executes a `Reference` in a `Scene` and returns the recorded signals as a `Rollout`.
What it can do besides is declared once, on the class, as `Capabilities`: callers ask
`backend.capabilities.films` rather than probing for methods or comparing names.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, ClassVar, Protocol

if TYPE_CHECKING:
    from stl_lfd.sim.executor import Command
    from stl_lfd.sim.reference import Reference, Rollout
    from stl_lfd.sim.scene import Scene

Observer = Callable[[float, Any], None]  # (simulated time, the backend's world), after each step


@dataclass(frozen=True)
class Capabilities:
    """What a backend can do.

    Attributes:
        plays_the_plan: what it records is the reference itself (no dynamics, nothing to learn
            about tracking).
        simulates: it simulates physics in simulated time (its speed is worth a ratio to real
            time, and long rollouts a progress bar).
        films: its observers receive a world with `render(camera) -> H x W x 3 uint8`.
        has_gui: it can show the execution in a window (`BackendOptions.gui`).
        measures_force: it records contact forces (`force`, `fx` ... `tz`) that can be non-zero.
        needs_command: it runs an external program (`BackendOptions.command`).
    """

    plays_the_plan: bool = False
    simulates: bool = False
    films: bool = False
    has_gui: bool = False
    measures_force: bool = False
    needs_command: bool = False

    def describe_rollout(self, recorded: float, elapsed: float, tracking_rms: float, tracking_max: float) -> str:
        """How a rollout of `recorded` seconds went, taking `elapsed` seconds, with the hand
        `tracking_rms`/`tracking_max` (m) off its reference: one phrase for the user."""
        tracking = f"tracking error RMS {1000 * tracking_rms:.2f} mm, worst {1000 * tracking_max:.2f} mm"
        if self.plays_the_plan:  # it plays the reference back: no speed or tracking to speak of
            return f"{recorded:.2f} s of the reference played back (no dynamics)"
        if self.simulates:
            return f"{recorded:.2f} s simulated in {elapsed:.2f} s ({recorded / max(elapsed, 1e-9):.0f}x real time); {tracking}"
        return f"{recorded:.2f} s executed by the command in {elapsed:.2f} s; {tracking}"


@dataclass(frozen=True)
class BackendOptions:
    """How to open a backend: the executor `command` and the run `folder` its exchange files go
    in (command backend), a GUI window (`gui`, backends that have one)."""

    command: "Command | None" = None
    folder: Path | None = None
    gui: bool = False


class Backend(Protocol):
    """What every backend offers: a name, its capabilities, `run`, and being closed when done
    (backends are context managers)."""

    name: ClassVar[str]
    capabilities: ClassVar[Capabilities]

    @classmethod
    def open(cls, options: BackendOptions) -> "Backend": ...

    def run(self, reference: "Reference", scene: "Scene", rate: float, observer: Observer | None = None) -> "Rollout": ...

    def close(self) -> None: ...

    def file_executions(self, folder: Path | None = None, trial: int | None = None) -> None: ...

    def __enter__(self) -> "Backend": ...

    def __exit__(self, *exception: object) -> None: ...


class BackendBase:
    """The parts every backend shares: `open` without options, and closing as a context manager."""

    name: ClassVar[str] = ""
    capabilities: ClassVar[Capabilities] = Capabilities()

    @classmethod
    def open(cls, options: BackendOptions) -> "BackendBase":
        return cls()

    def close(self) -> None:
        pass

    def file_executions(self, folder: Path | None = None, trial: int | None = None) -> None:
        """Where the next executions belong: the run directory `folder` and the `trial` (a
        backend that files each execution, the command backend, keeps them; the others have
        nothing to file)."""

    def __enter__(self) -> "BackendBase":
        return self

    def __exit__(self, *exception: object) -> None:
        self.close()
