"""The `stlopt` command line. Each command parses its options and calls the library.

Data other programs read goes to stdout; messages, warnings and errors go to stderr. A user
error prints one `error: ...` line (plus the offending spec line and a caret) and exits with
the code of its class in `stl_lfd.errors`; usage errors exit 2.

    program.py      the Typer application, `main`, errors and Ctrl-C, progress bars and tables
    options.py      choices, options and option values several commands share
    robustness.py   stlopt robustness
    skills.py       stlopt learn, retrieve
    execution.py    stlopt rollout, replay
    runs.py         stlopt optimize, ask, tell, sweep
    reports.py      stlopt report, dashboard

The command modules register their commands with `app` when imported, in the order `stlopt
--help` lists them.
"""

import importlib

from stl_lfd.cli.program import app, main

for _commands in ("robustness", "skills", "execution", "runs", "reports"):
    importlib.import_module(f"stl_lfd.cli.{_commands}")

__all__ = ["app", "main"]
