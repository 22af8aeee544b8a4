"""The figures of a report, one `FigureSpec` each (`base.py`), grouped by what they show:

    paths.py       trajectories, region_distances, tilt: where the hand went
    scores.py      robustness, components, gp_slices, compare: how good the trials were
    skills.py      transitions, durations: what the skills became
    contact.py     forces, wrench, objects: what was touched
    tracking.py    tracking: how the robot followed its plans

`FIGURES` is the registry: a new figure is a `FigureSpec` subclass and a line here.
"""

from __future__ import annotations

from stl_lfd.report.figures.base import FigureSpec, ReportOptions
from stl_lfd.report.figures.contact import Forces, ObjectSignals, Wrench
from stl_lfd.report.figures.paths import RegionDistances, Tilt, Trajectories
from stl_lfd.report.figures.scores import Compare, Components, GpSlices, Robustness
from stl_lfd.report.figures.skills import Durations, Transitions
from stl_lfd.report.figures.tracking import Tracking

# In the order index.html shows them.
FIGURES: tuple[FigureSpec, ...] = (
    Trajectories(),
    RegionDistances(),
    Robustness(),
    Components(),
    GpSlices(),
    Transitions(),
    Durations(),
    Forces(),
    Wrench(),
    ObjectSignals(),
    Tilt(),
    Tracking(),
    Compare(),
)


def figure_named(name: str) -> FigureSpec:
    """The registered figure called `name` (KeyError for none)."""
    for figure in FIGURES:
        if figure.name == name:
            return figure
    raise KeyError(name)


__all__ = ["FIGURES", "FigureSpec", "ReportOptions", "figure_named"]
