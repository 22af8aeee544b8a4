"""What a report figure is (`FigureSpec`), what every figure may use (`ReportOptions`), and the
drawing conventions the figures share: trials light to dark in trial order, the unoptimised
skill dashed, the best trial in red."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import numpy as np
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure

from stl_lfd.files import atomic_output
from stl_lfd.report.run_data import RunData

BEST = "tab:red"
INITIAL = "0.2"


@dataclass(frozen=True)
class ReportOptions:
    """What the user asked of a report beyond the run: `compare`, other runs (loaded) whose
    best-so-far robustness is drawn with the run's; `gp_parameters`, the GP slices' parameters
    (None: the most relevant)."""

    compare: tuple[RunData, ...] = ()
    gp_parameters: tuple[str, ...] | None = None


class FigureSpec:
    """One figure: `name` (its file is NAME.png), whether it `applies` to what it draws (a run,
    for the figures of a report) and, when it does not, the reason (`left_out`, shown in
    index.html), how to `draw` it and its `caption`. A new figure of a run is a subclass plus a
    line in `stl_lfd.report.figures.FIGURES`."""

    name: ClassVar[str]
    left_out: ClassVar[str] = ""

    def applies(self, run: RunData, options: ReportOptions) -> bool:
        """Whether the run has what the figure shows (the default: always)."""
        return True

    def draw(self, subject: Any, options: ReportOptions) -> Figure:
        """The figure of a run it `applies` to (a `SkillDrawing`, a sweep folder: of those)."""
        raise NotImplementedError

    def caption(self, subject: Any) -> str:
        raise NotImplementedError


def save_figure(figure: Figure, path: Path, dpi: int = 100) -> None:
    """Write `figure` to `path` (PNG, SVG or PDF by its suffix), whole or not at all."""
    with atomic_output(Path(path)) as temporary:
        figure.savefig(temporary, dpi=dpi)


def trial_colors(count: int) -> list[tuple]:
    """Light to dark grey-blue in trial order."""
    return [to_rgba("tab:blue", alpha=0.15 + 0.6 * index / max(count - 1, 1)) for index in range(count)]


def per_trial(axes, run: RunData, curves: dict[int, tuple[np.ndarray, np.ndarray]]) -> None:
    """Each trial's curve (trial number -> times, values; 0 the unoptimised skill) in its
    colour, the unoptimised one dashed and the best one in red, both labelled."""
    numbers = [number for number in curves if number > 0]
    for color, number in zip(trial_colors(len(numbers)), numbers):
        axes.plot(*curves[number], color=color, lw=1)
    if 0 in curves:
        axes.plot(*curves[0], color=INITIAL, ls="--", label="unoptimised")
    if run.best is not None and run.best.trial in curves:
        axes.plot(*curves[run.best.trial], color=BEST, lw=2, label="best")


def best_in_words(run: RunData) -> str:
    """How captions name the best trial's curve."""
    return f"the best (trial {run.best.trial}) in red" if run.best is not None else "no best trial yet"


def numbered_in_words(run: RunData) -> str:
    """How captions describe curves drawn by `per_trial`."""
    return "darker in trial order, the unoptimised skill dashed, " + best_in_words(run)
