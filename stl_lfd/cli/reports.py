"""`stlopt report`: the figures and index.html of a run, or the table of a sweep."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Optional

import typer

from stl_lfd.cli.program import PlainUsage, app, print_table, user_errors
from stl_lfd.errors import ConfigError


@app.command(cls=PlainUsage)
def report(
    run_dir: Path = typer.Argument(..., metavar="RUN_DIR", help="Run directory written by 'stlopt optimize' (or a sweep folder)."),
    out: Optional[Path] = typer.Option(None, "--out", help="Folder for the figures and index.html (default: RUN_DIR/report)."),
    compare: list[Path] = typer.Option([], "--compare", help="Another run directory to compare best-so-far robustness with (repeatable)."),
    gp_parameter: list[str] = typer.Option(
        [], "--gp-parameter", help="Parameter for the GP slice figure, e.g. 'mean[3].x' (repeatable; default: the two most relevant)."
    ),
) -> None:
    """Write the figures of an optimisation run (PNG) and an index.html that explains them.

    index.html: the verdict, the task (spec, what was optimised, method and budget), the
    commands to replay or continue, and each figure with its caption. Figures, where the run
    has the data: trajectories.png (paths from above and from the side), region_distances.png,
    robustness.png, components.png (each part of the spec and what they compose to),
    gp_slices.png, transitions.png (when transitions are optimised), durations.png, forces.png
    (when something was touched), tilt.png (when the hand turned), tracking.png (how the
    robot followed its plans, when the run learned it), compare.png (--compare).
    The paths of the files go to stdout. For a folder of 'stlopt sweep': its table (stdout) and
    sweep.png, redrawn from its runs.

    Example:

    \b
        stlopt report runs/phi1 --compare runs/phi1-random
    """
    from stl_lfd.report import write_report

    if (run_dir / "sweep.csv").is_file() and not (run_dir / "trials.jsonl").exists():
        _report_sweep(run_dir, out, bool(compare or gp_parameter))
        return
    with user_errors():
        index, pictures = write_report(run_dir, out, compare, gp_parameter or None)
    for path in pictures:
        print(path)
    print(index)
    print(f"wrote {len(pictures)} figures; open {index}", file=sys.stderr)


def _report_sweep(folder: Path, out: Optional[Path], run_options: bool) -> None:
    from stl_lfd.report.sweep import TABLE_HEADER, sweep_groups, table_rows, write_sweep_figure

    with user_errors():
        if out is not None or run_options:
            raise ConfigError(f"{folder}: a sweep folder's report is its table and sweep.png; --out, --compare and --gp-parameter are for run directories")
        figure = write_sweep_figure(folder)
        groups = sweep_groups(folder)
    print_table(TABLE_HEADER, table_rows(groups))
    print(f"wrote {figure}", file=sys.stderr)


@app.command(cls=PlainUsage)
def dashboard(
    folder: Path = typer.Argument(Path("runs"), metavar="[RUNS_DIR]", help="The folder of runs and sweeps to show (default: runs)."),
    host: str = typer.Option("127.0.0.1", "--host", help="The address to listen on (0.0.0.0: every network the machine is on)."),
    port: int = typer.Option(8050, "--port", help="The port to listen on (0: any free one)."),
) -> None:
    """Show the runs and sweeps under a folder in the browser, live, until Ctrl-C.

    The page lists the runs (their state, trials and best robustness) and sweeps; a run's page
    shows its trials as they are recorded: robustness and the spec's parts over trials, the
    latest and best paths with the spec's regions and the scene's objects, the signals the
    spec constrains over time, tracking errors, and the trials an ask/tell run has handed out.
    It only reads the run directories; everything it serves comes from installed packages.

    Examples:

    \b
        stlopt dashboard                      # runs/, at http://127.0.0.1:8050/
        stlopt dashboard runs/sweeps --port 8060
        stlopt dashboard --host 0.0.0.0       # seen from the lab's other machines
    """
    with user_errors(on_interrupt="dashboard stopped"):
        if not folder.is_dir():
            raise ConfigError(f"{folder}: no such folder (the dashboard shows the runs under a folder, default runs/)")
        from stl_lfd.dashboard.app import serve

        serve(folder, host, port, ready=lambda url: print(f"stlopt dashboard on {url} (Ctrl-C stops it)", file=sys.stderr, flush=True))
