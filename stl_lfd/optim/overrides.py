"""`Overrides`: the settings of a task file that a command line (or a sweep) replaces, in one
place: which they are, how the command line spells them, and how they apply to a task."""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

from stl_lfd.errors import ConfigError
from stl_lfd.optim.task import Task
from stl_lfd.poses import Pose
from stl_lfd.sim.command import Command

OPTIMIZER_KEYS = ("seed", "initial", "trials", "method", "workers")  # fields of `Optimizer`; the others are fields of `Task`


def _option(spelling: str) -> Any:
    return field(default=None, metadata={"option": spelling})


@dataclass(frozen=True)
class Overrides:
    """Settings given on top of a task file; None keeps the file's. `trials` (the budget) may
    change when a run is resumed; the others define the problem and may not."""

    spec: Path | None = _option("--spec")
    backend: str | None = _option("--backend")
    command: Command | None = _option("--command")
    placements: tuple[dict[str, Pose], ...] | None = _option("--place")
    seed: int | None = _option("--seed")
    initial: int | None = _option("--init")
    trials: int | None = _option("--iterations")
    method: str | None = _option("--method")
    workers: int | None = _option("--workers")

    def given(self) -> dict[str, Any]:
        """The settings given (not None), by name."""
        return {item.name: getattr(self, item.name) for item in fields(self) if getattr(self, item.name) is not None}

    def applied_to(self, task: Task) -> Task:
        """`task` with these settings in place of its own (validated as a task file's are)."""
        given = self.given()
        try:
            optimizer = replace(task.optimizer, **{key: value for key, value in given.items() if key in OPTIMIZER_KEYS})
        except ConfigError as error:
            raise ConfigError(f"{task.source}: {error}") from None
        return replace(task, optimizer=optimizer, **{key: value for key, value in given.items() if key not in OPTIMIZER_KEYS})

    @staticmethod
    def option(name: str) -> str:
        """How the command line spells setting `name` (`--init` for `initial`)."""
        return next(item.metadata["option"] for item in fields(Overrides) if item.name == name)

    @staticmethod
    def setting(task: Task, name: str) -> Any:
        """The value of setting `name` in `task`."""
        return getattr(task.optimizer, name) if name in OPTIMIZER_KEYS else getattr(task, name)
