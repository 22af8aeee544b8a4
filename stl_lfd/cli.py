"""The `stlopt` command line. Each command parses its options and calls the library.

Data other programs read goes to stdout; messages, warnings and errors go to stderr. A user
error prints one `error: ...` line (plus the offending spec line and a caret) and exits with
the code of its class in `stl_lfd.errors`; usage errors exit 2.
"""

from __future__ import annotations

import json
import math
import sys
import warnings
from contextlib import contextmanager
from enum import Enum
from pathlib import Path
from typing import Iterator, Optional

import typer

from stl_lfd import __version__
from stl_lfd.errors import StlLfdError

app = typer.Typer(
    help="Adapt demonstrated robot skills to Signal Temporal Logic requirements.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    context_settings={"help_option_names": ["-h", "--help"]},
)


class SemanticsOption(str, Enum):
    classic = "classic"
    new = "new"


def _print_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"warning: {message}", file=sys.stderr)


@contextmanager
def user_errors() -> Iterator[None]:
    """Turn library errors into one stderr line and the error class's exit code."""
    warnings.showwarning = _print_warning
    try:
        yield
    except StlLfdError as error:
        print(f"error: {error}", file=sys.stderr)
        raise typer.Exit(code=error.exit_code) from None


def _version(value: bool) -> None:
    if value:
        print(f"stlopt {__version__}")
        raise typer.Exit()


@app.callback()
def main(
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True, help="Print the version and exit."),
) -> None:
    """Adapt demonstrated robot skills to Signal Temporal Logic requirements."""


@app.command()
def robustness(
    spec: Path = typer.Argument(..., help="STL specification file (.stl)."),
    signal_csv: str = typer.Argument(..., help="Signal CSV with a time column t; '-' reads stdin."),
    semantics: SemanticsOption = typer.Option(SemanticsOption.classic, help="classic space robustness or the paper's new robustness."),
    nu: float = typer.Option(1.0, help="Sharpness of the new robustness (> 0); larger is closer to classic."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object instead of the bare number."),
) -> None:
    """Print the robustness of a recorded signal with respect to a specification.

    The robustness is the value at the first sample; it is positive exactly when the signal
    satisfies the specification. Without --json, stdout gets the number and stderr a verdict.

    Example:

        stlopt robustness specs/example.stl examples/s1.csv --semantics new --json
    """
    from stl_lfd.evaluate import evaluate_file

    with user_errors():
        result = evaluate_file(spec, signal_csv, semantics.value, nu)
    if as_json:
        print(json.dumps(result.to_json()))
    else:
        print(f"{result.robustness:.10g}")
        print("satisfied" if result.satisfied else "violated", file=sys.stderr)


if __name__ == "__main__":
    app()
