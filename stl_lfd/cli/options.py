"""What several commands parse alike: choices built from the library's own lists, shared
options, and the conversion of option values (executor commands, placements) into the
library's objects."""

from __future__ import annotations

import dataclasses
from enum import Enum
from pathlib import Path
from typing import Optional

import typer

from stl_lfd.choices import SEMANTICS
from stl_lfd.errors import ConfigError, ModelError
from stl_lfd.optim.methods import method_names
from stl_lfd.sim.registry import backend_names


def choices(name: str, values: tuple[str, ...]) -> type[Enum]:
    """A command-line choice built from the library's own list of values (one definition)."""
    return Enum(name, [(value, value) for value in values], type=str)


SemanticsOption = choices("SemanticsOption", SEMANTICS)
BackendOption = choices("BackendOption", backend_names())
MethodOption = choices("MethodOption", method_names())

FIGURE_SUFFIXES = (".png", ".pdf", ".svg")
SIGNAL_SUFFIXES = (".csv",)
PLACE_HELP = "Place an object frame of the scene: NAME=x,y[,z[,yaw]] (metres, yaw in radians; z and yaw default to the scene's). Repeat for several frames."
COMMAND_HELP = "With --backend command: the executor to run, with {reference} and {signals} for the two CSV paths (no shell)."
COMMAND_TIMEOUT_HELP = "Seconds after which the executor is stopped and the trial fails (default: the task's, or 600)."

# Options that several commands share, defined once (Typer reads a parameter's default as its option).
CommandOption = typer.Option(None, "--command", help=COMMAND_HELP)
CommandTimeoutOption = typer.Option(None, "--command-timeout", help=COMMAND_TIMEOUT_HELP)
IterationsOption = typer.Option(None, "--iterations", "-N", help="Total number of trials N (default: the task's).")
InitOption = typer.Option(
    None, "--init", "-M", help="Initial trials M: scrambled Sobol points, or with method plan chosen on their plans (default: the task's)."
)
SeedOption = typer.Option(None, "--seed", help="Seed of the initial trials and of the acquisition optimiser.")


def command_of(text: Optional[str], timeout: Optional[float], task_command):
    """The executor command of --command/--command-timeout, None when neither is given."""
    from stl_lfd.sim import Command
    from stl_lfd.sim.executor import DEFAULT_TIMEOUT

    if text is not None:
        return Command.parse(text, timeout if timeout is not None else DEFAULT_TIMEOUT, cwd=Path.cwd())
    if timeout is None:
        return None
    if task_command is None:
        raise ConfigError("--command-timeout needs a command (--command, or 'command' in the task file)")
    if not timeout > 0:
        raise ConfigError(f"--command-timeout must be positive (got {timeout:g})")
    return dataclasses.replace(task_command, timeout=float(timeout))


def placements_of(scene_name: str, place: list[str]):
    """The one placement of --place options (None without any), checked against the scene."""
    if not place:
        return None
    from stl_lfd.sim.scene_file import load_scene, placement_from_options

    return (placement_from_options(load_scene(scene_name), place),)


def check_duration_and_rate(duration: Optional[float], rate: float) -> None:
    from stl_lfd.limits import samples_problem

    problem = samples_problem(duration, rate)
    if problem:
        raise ModelError(f"--duration/--rate: {problem}")
