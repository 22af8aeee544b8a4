"""The figures of a report, one `FigureSpec` each (`base.py`), grouped by what they show:

    paths.py       trajectories, region_distances, tilt: where the hand went
    scores.py      robustness, components, gp_slices, compare: how good the trials were
    skills.py      transitions, durations: what the skills became
    contact.py     forces, wrench, objects: what was touched
    tracking.py    tracking: how the robot followed its plans
    learned.py     skill: a learned skill (`stlopt learn --plot`)
    sweep.py       sweep: the runs of a sweep (`sweep.png`)

`FIGURES` is the registry of a run's figures: a new one is a `FigureSpec` subclass and a line
there. `LEARNED_SKILL` and `SWEEP` draw the other two things the tool draws; every figure is
written by `save_figure`.
"""

from __future__ import annotations

from stl_lfd.report.figures.base import FigureSpec, ReportOptions, save_figure
from stl_lfd.report.figures.contact import Forces, ObjectSignals, Wrench
from stl_lfd.report.figures.learned import SkillDrawing, SkillFigure
from stl_lfd.report.figures.paths import RegionDistances, Tilt, Trajectories
from stl_lfd.report.figures.scores import Compare, Components, GpSlices, Robustness
from stl_lfd.report.figures.skills import Durations, Transitions
from stl_lfd.report.figures.sweep import SweepCurves
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
LEARNED_SKILL = SkillFigure()
SWEEP = SweepCurves()


def figure_named(name: str) -> FigureSpec:
    """The registered figure called `name` (KeyError for none)."""
    for figure in (*FIGURES, LEARNED_SKILL, SWEEP):
        if figure.name == name:
            return figure
    raise KeyError(name)


__all__ = ["FIGURES", "LEARNED_SKILL", "SWEEP", "FigureSpec", "ReportOptions", "SkillDrawing", "figure_named", "save_figure"]
