"""An executor command: the external program the `command` backend runs for each execution
(see `stl_lfd.sim.command` for how it is run, and its placeholders)."""

from __future__ import annotations

import difflib
import re
import shlex
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from stl_lfd.errors import ConfigError

DEFAULT_TIMEOUT = 600.0  # seconds: a real trial takes about a minute
PLACEHOLDERS = ("reference", "signals", "trial", "run_dir", "scene", "rate")


@dataclass(frozen=True)
class Command:
    """An executor command.

    Attributes:
        run: the argument list (with placeholders), or with `shell` one shell command line.
        timeout: seconds after which the command is stopped and the execution fails.
        shell: run `run[0]` with `/bin/sh -c` (placeholders are substituted quoted).
        cwd: the working directory (default: the current one).
    """

    run: tuple[str, ...]
    timeout: float = DEFAULT_TIMEOUT
    shell: bool = False
    cwd: Path | None = None

    @classmethod
    def parse(cls, text: str | list[str], timeout: float = DEFAULT_TIMEOUT, shell: bool = False, cwd: Path | None = None) -> "Command":
        """A command from a string (split like a shell unless `shell`) or an argument list."""
        if isinstance(text, list):
            if shell:
                raise ConfigError("a shell command must be one string, not a list")
            run = tuple(str(item) for item in text)
        else:
            try:
                run = (text,) if shell else tuple(shlex.split(text))
            except ValueError as error:
                raise ConfigError(f"the command {text!r} cannot be split into arguments ({error})") from None
        if not run or not run[0].strip():
            raise ConfigError("the command is empty")
        misspelt = _misspelt_placeholder(run)
        if misspelt is not None:
            known = ", ".join("{" + name + "}" for name in PLACEHOLDERS)
            raise ConfigError(f"the command has {{{misspelt[0]}}}: did you mean {{{misspelt[1]}}}? (its placeholders: {known})")
        if not timeout > 0:
            raise ConfigError(f"the command's timeout must be positive (got {timeout})")
        return cls(run, float(timeout), shell, cwd)

    def arguments(self, values: dict[str, str]) -> list[str] | str:
        """The command with its placeholders replaced by `values`."""
        quote = shlex.quote if self.shell else str
        arguments = []
        for argument in self.run:
            for name, value in values.items():
                argument = argument.replace("{" + name + "}", quote(value))
            arguments.append(argument)
        return arguments[0] if self.shell else arguments

    def to_dict(self) -> dict[str, Any]:
        """The task-file form: `run` (a list, or the string with `shell`), `timeout`, `shell`, `cwd`."""
        data: dict[str, Any] = {"run": self.run[0] if self.shell else list(self.run), "timeout": self.timeout, "shell": self.shell}
        if self.cwd is not None:
            data["cwd"] = str(Path(self.cwd).resolve())
        return data

    def shown(self) -> str:
        return self.run[0] if self.shell else shlex.join(self.run)


def _misspelt_placeholder(run: tuple[str, ...]) -> tuple[str, str] | None:
    """`({name}, the placeholder it is close to)` for the first `{name}` in the command that is
    a near-miss of a placeholder (`{signal}`); other braces (`awk '{print}'`) are the command's."""
    for argument in run:
        for name in re.findall(r"(?<![$\\{]){([A-Za-z_][A-Za-z0-9_]*)}", argument):
            close = difflib.get_close_matches(name, PLACEHOLDERS, n=1, cutoff=0.75)
            if name not in PLACEHOLDERS and close:
                return name, close[0]
    return None
