"""The results of a sweep: the table of `stlopt sweep` and its comparison figure `sweep.png`
(`report/figures/sweep.py`)."""

from __future__ import annotations

from pathlib import Path

from stl_lfd.errors import RunError
from stl_lfd.optim.runs.sweep import Group, aggregate, read_table
from stl_lfd.report.figures import SWEEP, save_figure

FIGURE_FILE = "sweep.png"


def table_rows(groups: list[Group]) -> list[list[str]]:
    """The printed table: task, variant, method, success rate, median trials to the first
    satisfaction, median best robustness, median wall time per run."""
    rows = []
    for group in groups:
        first = f"{group.median_first_satisfied:g}" if group.median_first_satisfied is not None else "-"
        best = f"{group.median_best_robustness:+.5f}" if group.median_best_robustness is not None else "-"
        success = f"{group.satisfied}/{group.runs} ({100 * group.success_rate:.0f} %)"
        rows.append([group.task, group.variant or "-", group.method, success, first, best, f"{group.median_wall_seconds:.1f} s"])
    return rows


TABLE_HEADER = ["task", "variant", "method", "satisfied", "median first satisfied trial", "median best robustness", "median wall time per run"]


def write_sweep_figure(out: Path) -> Path:
    """Write `sweep.png` into the sweep folder `out`; returns its path."""
    import matplotlib

    matplotlib.use("Agg")
    path = Path(out) / FIGURE_FILE
    try:
        figure = SWEEP.draw(Path(out))  # read first: a damaged cell is an input's fault, not the figure's
    except OSError as error:
        raise RunError(f"{error.filename or out}: cannot read ({error.strerror or error})") from None
    save_figure(figure, path)
    return path


def sweep_groups(out: Path) -> list[Group]:
    return aggregate(read_table(out))
