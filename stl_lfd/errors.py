"""Exceptions of stl_lfd.

Every error a user can cause derives from `StlLfdError`; the command line turns each class
into one line on stderr and its own exit code (`exit_code`), never a traceback.
"""

from __future__ import annotations

from stl_lfd.key_positions import with_position


class StlLfdError(Exception):
    """Base class of all user-facing errors."""

    exit_code = 1


class SpecError(StlLfdError):
    """An STL specification is malformed or does not fit the signals.

    Attributes:
        message: what is wrong, without the location.
        source: the file (or `<string>`) the specification came from.
        line, column: 1-based position of the offending text, 0 when unknown.
        context: the offending source line with a caret under the column, or "".
    """

    exit_code = 3

    def __init__(
        self,
        message: str,
        source: str = "<string>",
        line: int = 0,
        column: int = 0,
        context: str = "",
    ) -> None:
        self.message = message
        self.source = source
        self.line = line
        self.column = column
        self.context = context
        super().__init__(str(self))

    def located(self, source: str, text: str | None = None) -> "SpecError":
        """A copy naming `source` and showing the offending line of `text` (none without it)."""
        context = self.context
        if text is not None and self.line:
            context = caret_context(text, self.line, self.column)
        return type(self)(self.message, source, self.line, self.column, context)

    def __str__(self) -> str:
        if self.source == "<string>" and not self.line:  # not about a place in a text: no prefix
            head = self.message
        else:
            where = self.source + (f":{self.line}:{self.column}" if self.line else "")
            head = f"{where}: {self.message}"
        return f"{head}\n{self.context}" if self.context else head


class StlSyntaxError(SpecError):
    """The text is not a well-formed specification (bad token, unbalanced brackets, ...)."""


class StlNameError(SpecError):
    """Undefined or recursive formula names, or signals the trace does not have."""


class SignalError(StlLfdError):
    """A signal or demonstration file (CSV) is missing, malformed or inconsistent."""

    exit_code = 4


class ConfigError(StlLfdError):
    """A task, scene or behaviour file has an unknown key or a value that makes no sense.

    A message `FILE: 'key' ...` about a YAML file that was read gets the key's line and column.
    """

    exit_code = 5

    def __init__(self, message: str) -> None:
        super().__init__(with_position(message))


class ModelError(StlLfdError):
    """A skill model cannot be learned, loaded or used as asked."""

    exit_code = 6


class ExecutionError(StlLfdError):
    """A rollout failed (simulator error, NaN in the trajectory, unreachable scene)."""

    exit_code = 7


class OutputError(StlLfdError):
    """An output path cannot be written: a missing or read-only folder, a folder where a file
    is expected, an unknown suffix, or a full disk."""

    exit_code = 8


class RunError(StlLfdError):
    """A run directory is damaged, in use by another process, or not the run asked for."""

    exit_code = 9


class WaitError(RunError):
    """No trial can be handed out until a pending one is told: as many are out as the run's
    workers allow, or the next is chosen from trials not told yet. A fleet's script asks again
    after its next tell."""

    exit_code = 10


class BusyError(RunError):
    """The run is being written by another stlopt process (a `tell` or `ask` of another robot,
    or a run): try again in a moment; unlike a damaged run, nothing is wrong with it."""

    exit_code = 11


def caret_context(text: str, line: int, column: int) -> str:
    """The `line`-th line of `text` (1-based) and a caret under `column` (1-based)."""
    lines = text.splitlines()
    if not 1 <= line <= len(lines):
        return ""
    source_line = lines[line - 1].rstrip("\n")
    return f"  {source_line}\n  {' ' * max(column - 1, 0)}^"
