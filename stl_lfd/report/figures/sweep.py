"""The figure of a sweep (`sweep.png`): the median best-so-far robustness per trial for each
method, with its range over the seeds, one panel per task and variant."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import ClassVar

import numpy as np
from matplotlib.figure import Figure

from stl_lfd.optim.runs.directory import RunDirectory
from stl_lfd.optim.runs.sweep import RUNS_DIR, read_table
from stl_lfd.optim.trials import best_so_far, robustness_of
from stl_lfd.report.figures.base import FigureSpec, ReportOptions


def run_best_so_far(run_dir: Path) -> np.ndarray:
    """Best robustness after each trial of a run (NaN before the first success)."""
    return best_so_far(robustness_of(RunDirectory(run_dir).trials()))


class SweepCurves(FigureSpec):
    """The best-so-far curves of a sweep folder's runs, grouped by task, variant and method."""

    name: ClassVar[str] = "sweep"

    def draw(self, out: Path, options: ReportOptions = ReportOptions()) -> Figure:
        panels: dict[tuple[str, str], dict[str, list[np.ndarray]]] = {}
        for record in read_table(out):
            curves = panels.setdefault((record["task"], record["variant"]), {})
            curves.setdefault(record["method"], []).append(run_best_so_far(Path(out) / RUNS_DIR / record["cell"]))
        figure = Figure(figsize=(6.5 * max(len(panels), 1), 4), layout="constrained")
        for axes, ((task, variant), curves) in zip(figure.subplots(1, max(len(panels), 1), squeeze=False)[0], panels.items()):
            for index, (method, runs) in enumerate(curves.items()):
                _draw_method(axes, runs, f"C{index}", f"{method} ({len(runs)} seeds)")
            axes.axhline(0.0, color="k", lw=1)
            axes.set(xlabel="trial", ylabel="best robustness so far", title=task + (f" ({variant})" if variant else ""))
            axes.legend(loc="lower right", fontsize=8)
        return figure

    def caption(self, out: Path) -> str:
        return "For each method, the median over the seeds of the best robustness after each trial (line) and its range (band); above 0 satisfies the spec."


def _draw_method(axes, runs: list[np.ndarray], color: str, label: str) -> None:
    """The median and range over `runs` of their best-so-far robustness, trial by trial."""
    length = max(len(run) for run in runs)
    stacked = np.full((len(runs), length), np.nan)
    for row, run in enumerate(runs):
        stacked[row, : len(run)] = run
    trials = np.arange(1, length + 1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-NaN columns: no seed succeeded yet
        median, low, high = np.nanmedian(stacked, axis=0), np.nanmin(stacked, axis=0), np.nanmax(stacked, axis=0)
    axes.fill_between(trials, low, high, color=color, alpha=0.15, step="post")
    axes.step(trials, median, where="post", color=color, lw=2, label=label)
