"""The figure of a learned skill (`stlopt learn --plot`): demonstrations, states as covariance
ellipses, the retrieval."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import ClassVar

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Ellipse

from stl_lfd.hsmm import LearnedSkill, retrieve
from stl_lfd.report.figures.base import FigureSpec, ReportOptions, save_figure


@dataclass(frozen=True)
class SkillDrawing:
    """What the figure of a learned skill shows.

    Attributes:
        demos: `T_i x D` demonstrations resampled at `sample_period`.
        means: `K x D` state means; covariances: `K x D x D`.
        retrieved: `T x D` retrieved trajectory at `sample_period`.
        signal_names: the D names.
        axes_pair: the two signals of the left panel's plane (default the first two, e.g. x-y).
    """

    demos: list[np.ndarray]
    means: np.ndarray
    covariances: np.ndarray
    retrieved: np.ndarray
    sample_period: float
    signal_names: list[str]
    axes_pair: tuple[int, int] = (0, 1)


class SkillFigure(FigureSpec):
    """Two panels: the plane of two signals, and every signal over time."""

    name: ClassVar[str] = "skill"

    def draw(self, skill: SkillDrawing, options: ReportOptions = ReportOptions()) -> Figure:
        figure = Figure(figsize=(11, 4.5), layout="constrained")
        plane, timeline = figure.subplots(1, 2)
        _draw_plane(plane, skill)
        _draw_timeline(timeline, skill)
        return figure

    def caption(self, skill: SkillDrawing) -> str:
        return (
            f"The {len(skill.demos)} demonstrations (grey), the model's {len(skill.means)} states as ellipses of 2 standard deviations "
            "(numbered in order) and the path the model retrieves (red); right, every signal over time."
        )


def _draw_plane(axes, skill: SkillDrawing) -> None:
    """The demonstrations, the states' ellipses and the retrieval in the plane of two signals."""
    first, second = skill.axes_pair
    for index, demo in enumerate(skill.demos):
        axes.plot(demo[:, first], demo[:, second], color="0.65", lw=1, label="demonstrations" if index == 0 else None)
    for state, (mean, covariance) in enumerate(zip(skill.means, skill.covariances)):
        values, vectors = np.linalg.eigh(covariance[np.ix_([first, second], [first, second])])
        angle = np.degrees(np.arctan2(vectors[1, -1], vectors[0, -1]))
        width, height = 2 * 2 * np.sqrt(np.maximum(values[::-1], 0))  # 2 standard deviations
        axes.add_patch(Ellipse((mean[first], mean[second]), width, height, angle=angle, alpha=0.25, color=f"C{state % 10}"))
        axes.annotate(str(state + 1), (mean[first], mean[second]), ha="center", va="center", fontsize=9, weight="bold")
    axes.plot(skill.retrieved[:, first], skill.retrieved[:, second], color="C3", lw=2, label="retrieved")
    axes.set(xlabel=skill.signal_names[first], ylabel=skill.signal_names[second], title="states (2 std ellipses) and paths")
    axes.set_aspect("equal", adjustable="datalim")
    axes.legend(loc="best", fontsize=8)


def _draw_timeline(axes, skill: SkillDrawing) -> None:
    """Every signal over time: the demonstrations faint, the retrieval bold."""
    for demo in skill.demos:
        times = np.arange(len(demo)) * skill.sample_period
        for dimension in range(demo.shape[1]):
            axes.plot(times, demo[:, dimension], color=f"C{dimension}", alpha=0.25, lw=1)
    times = np.arange(len(skill.retrieved)) * skill.sample_period
    for dimension, name in enumerate(skill.signal_names):
        axes.plot(times, skill.retrieved[:, dimension], color=f"C{dimension}", lw=2, label=name)
    axes.set(xlabel="time (s)", title="signals over time (faint: demonstrations)")
    axes.legend(loc="best", fontsize=8)


def write_skill_figure(skill: LearnedSkill, path: Path) -> None:
    """Draw a skill `stlopt learn` learned (as its demonstrations show it) into `path`."""
    shown, model = skill.shown, skill.model
    drawing = SkillDrawing(skill.sequences, shown.means_, shown.covars_, retrieve(shown).positions, model.sample_period_, model.signal_names_)
    save_figure(SkillFigure().draw(drawing), path, dpi=110)
