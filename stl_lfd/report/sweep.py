"""The results of a sweep: the table of `stlopt sweep` and its comparison figure `sweep.png`
(median best-so-far robustness per trial for each method, one panel per task and variant)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from stl_lfd.errors import RunError
from stl_lfd.files import atomic_output
from stl_lfd.optim.runs.directory import RunDirectory
from stl_lfd.optim.runs.sweep import RUNS_DIR, Group, aggregate, read_table
from stl_lfd.optim.trials import best_so_far, robustness_of

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


def run_best_so_far(run_dir: Path) -> np.ndarray:
    """Best robustness after each trial of a run (NaN before the first success)."""
    return best_so_far(robustness_of(RunDirectory(run_dir).trials()))


def sweep_figure(out: Path) -> Figure:
    """Median (and range over seeds of) best-so-far robustness per trial, per method."""
    records = read_table(out)
    panels: dict[tuple[str, str], dict[str, list[np.ndarray]]] = {}
    for record in records:
        curves = panels.setdefault((record["task"], record["variant"]), {})
        curves.setdefault(record["method"], []).append(run_best_so_far(Path(out) / RUNS_DIR / record["cell"]))
    figure = Figure(figsize=(6.5 * max(len(panels), 1), 4), layout="constrained")
    for axes, ((task, variant), curves) in zip(np.atleast_1d(figure.subplots(1, max(len(panels), 1), squeeze=False)[0]), panels.items()):
        for index, (method, runs) in enumerate(curves.items()):
            length = max(len(run) for run in runs)
            stacked = np.full((len(runs), length), np.nan)
            for row, run in enumerate(runs):
                stacked[row, : len(run)] = run
            trials = np.arange(1, length + 1)
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns: no seed succeeded yet
                median, low, high = np.nanmedian(stacked, axis=0), np.nanmin(stacked, axis=0), np.nanmax(stacked, axis=0)
            axes.fill_between(trials, low, high, color=f"C{index}", alpha=0.15, step="post")
            axes.step(trials, median, where="post", color=f"C{index}", lw=2, label=f"{method} ({len(runs)} seeds)")
        axes.axhline(0.0, color="k", lw=1)
        axes.set(xlabel="trial", ylabel="best robustness so far", title=task + (f" ({variant})" if variant else ""))
        axes.legend(loc="lower right", fontsize=8)
    return figure


def write_sweep_figure(out: Path) -> Path:
    """Write `sweep.png` into the sweep folder `out`; returns its path."""
    import matplotlib

    matplotlib.use("Agg")
    path = Path(out) / FIGURE_FILE
    try:
        figure = sweep_figure(out)  # read first: a damaged cell is an input's fault, not the figure's
    except OSError as error:
        raise RunError(f"{error.filename or out}: cannot read ({error.strerror or error})") from None
    with atomic_output(path) as temporary:
        figure.savefig(temporary, dpi=100)
    return path


def sweep_groups(out: Path) -> list[Group]:
    return aggregate(read_table(out))
