"""The `stlopt` program: the Typer application every command registers with, how library
errors and Ctrl-C become exit codes, and the displays commands share (progress bars, tables)."""

from __future__ import annotations

import os
import signal
import sys
import warnings
from contextlib import contextmanager
from typing import Iterator

import typer
from typer.core import TyperArgument, TyperCommand

from stl_lfd.allocator import keep_freed_memory
from stl_lfd.errors import OutputError, StlLfdError
from stl_lfd.spelling import spelled_as

INTERRUPTED = 130  # what a shell reports for a process that SIGINT ended
# How the command line spells the settings that library messages name (`stl_lfd.spelling`).
SPELLINGS = {
    "backend": "--backend",
    "command": "--command",
    "compare": "--compare",
    "demos": "--demos",
    "frame": "--frame",
    "gp_parameters": "--gp-parameter",
    "host": "--host",
    "initial": "--init",
    "method": "--method",
    "min_spread": "--min-spread",
    "model": "--model",
    "out": "--out",
    "output": "-o",
    "place": "--place",
    "placements": "--place",
    "port": "--port",
    "ray": "--ray",
    "resume": "--resume",
    "seed": "--seed",
    "spec": "--spec",
    "trial": "--trial",
    "trials": "--iterations",
    "workers": "--workers",
}
_as_program = False  # run as the `stlopt` program (`main`), not called in-process (tests, the API)


class PlainUsage(TyperCommand):
    """Usage lines in the usual form, `stlopt optimize [OPTIONS] TASK_FILE`, which a user can copy."""

    def collect_usage_pieces(self, ctx: typer.Context) -> list[str]:
        arguments = [param.metavar or param.name.upper() for param in self.get_params(ctx) if isinstance(param, TyperArgument)]
        return [self.options_metavar] + arguments


app = typer.Typer(
    help="Adapt demonstrated robot skills to Signal Temporal Logic requirements.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
    rich_markup_mode=None,
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _print_warning(message, category, filename, lineno, file=None, line=None) -> None:
    print(f"warning: {message}", file=sys.stderr)


@contextmanager
def user_errors(on_interrupt: str = "interrupted") -> Iterator[None]:
    """Turn library errors into one stderr line and the error class's exit code, and Ctrl-C
    into the line `on_interrupt` and an interrupted exit (see `main`)."""
    with warnings.catch_warnings():  # restores the process's warning display afterwards
        warnings.showwarning = _print_warning
        try:
            yield
        except StlLfdError as error:
            print(f"error: {error}", file=sys.stderr)
            raise typer.Exit(code=error.exit_code) from None
        except KeyboardInterrupt:
            print(on_interrupt, file=sys.stderr)
            if _as_program:  # a second Ctrl-C while the run closes ends it by SIGINT at once, as `main` would
                signal.signal(signal.SIGINT, signal.SIG_DFL)
            raise typer.Exit(code=INTERRUPTED) from None


def main() -> None:
    """The `stlopt` program. After Ctrl-C it dies by SIGINT (not a plain exit 130), so that a
    shell loop of runs stops instead of going on to the next one."""
    global _as_program
    keep_freed_memory()
    _as_program = True
    try:
        app()
    except OSError as error:  # what no command turned into an error of its own: stdout on a full disk (/dev/full)
        where = error.filename or "cannot write the output"  # without a file name: stdout
        print(f"error: {where}: {error.strerror or error}", file=sys.stderr)
        sys.exit(OutputError.exit_code)
    except SystemExit as stop:
        if stop.code == INTERRUPTED:
            sys.stdout.flush()
            sys.stderr.flush()
            signal.signal(signal.SIGINT, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGINT)
        raise


def _version(value: bool) -> None:
    if value:
        from importlib.metadata import version

        print(f"stlopt {version('stlopt')}")
        raise typer.Exit()


@app.callback()
def _root(
    ctx: typer.Context,
    version: bool = typer.Option(False, "--version", callback=_version, is_eager=True, help="Print the version and exit."),
) -> None:
    """Adapt demonstrated robot skills to Signal Temporal Logic requirements."""
    ctx.call_on_close(spelled_as(SPELLINGS))  # messages name options as typed here, for this command only


def one_blas_thread() -> None:
    """One OpenBLAS thread for a command that does no linear algebra, unless the user chose:
    loading numpy otherwise starts one per core, which spin for a while (about 0.08 s of CPU
    on two cores, a third of a small `stlopt robustness`). Too late once numpy is loaded."""
    if "numpy" not in sys.modules:
        os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")


def to_stderr(message: str) -> None:
    """Print a note for the user on stderr (what a command hands the library to say as it goes)."""
    print(message, file=sys.stderr)


def print_table(header: list[str], rows: list[list[str]]) -> None:
    """A plain table on stdout: columns padded to their widest cell."""
    widths = [max(len(str(row[column])) for row in [header, *rows]) for column in range(len(header))]
    for row in [header, *rows]:
        print("  ".join(str(cell).ljust(width) for cell, width in zip(row, widths)).rstrip())


@contextmanager
def progress_bar(description: str, total: int) -> Iterator:
    """A rich progress bar on stderr; yields a function taking the number of steps done."""
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(), TimeRemainingColumn())
    with Progress(*columns, console=Console(stderr=True), transient=True) as progress:
        task = progress.add_task(description, total=total)
        yield lambda done: progress.update(task, completed=done)
