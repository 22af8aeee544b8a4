"""The figure of a learned skill: demonstrations, states as covariance ellipses, the retrieval."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Ellipse

from stl_lfd.files import atomic_output
from stl_lfd.hsmm import LearnedSkill, retrieve


def write_skill_figure(skill: LearnedSkill, path: Path) -> None:
    """Draw `skill_figure` of a skill `stlopt learn` learned (as its demonstrations show it)
    into `path`."""
    shown, model = skill.shown, skill.model
    figure = skill_figure(skill.sequences, shown.means_, shown.covars_, retrieve(shown).positions, model.sample_period_, model.signal_names_)
    with atomic_output(path) as temporary:
        figure.savefig(temporary, dpi=110)


def skill_figure(
    demos: list[np.ndarray],
    means: np.ndarray,
    covariances: np.ndarray,
    retrieved: np.ndarray,
    sample_period: float,
    signal_names: list[str],
    axes_pair: tuple[int, int] = (0, 1),
) -> Figure:
    """Two panels: the plane of two signals (default the first two, e.g. x-y) and every
    signal over time.

    Args:
        demos: `T_i x D` demonstrations resampled at `sample_period`.
        means: `K x D` state means; covariances: `K x D x D`.
        retrieved: `T x D` retrieved trajectory at `sample_period`.
        signal_names: the D names.
    """
    figure = Figure(figsize=(11, 4.5), layout="constrained")
    plane, timeline = figure.subplots(1, 2)
    first, second = axes_pair
    for index, demo in enumerate(demos):
        plane.plot(demo[:, first], demo[:, second], color="0.65", lw=1, label="demonstrations" if index == 0 else None)
        times = np.arange(len(demo)) * sample_period
        for dimension in range(demo.shape[1]):
            timeline.plot(times, demo[:, dimension], color=f"C{dimension}", alpha=0.25, lw=1)
    for state, (mean, covariance) in enumerate(zip(means, covariances)):
        block = covariance[np.ix_([first, second], [first, second])]
        values, vectors = np.linalg.eigh(block)
        angle = np.degrees(np.arctan2(vectors[1, -1], vectors[0, -1]))
        width, height = 2 * 2 * np.sqrt(np.maximum(values[::-1], 0))  # 2 standard deviations
        plane.add_patch(Ellipse((mean[first], mean[second]), width, height, angle=angle, alpha=0.25, color=f"C{state % 10}"))
        plane.annotate(str(state + 1), (mean[first], mean[second]), ha="center", va="center", fontsize=9, weight="bold")
    plane.plot(retrieved[:, first], retrieved[:, second], color="C3", lw=2, label="retrieved")
    plane.set_xlabel(f"{signal_names[first]}")
    plane.set_ylabel(f"{signal_names[second]}")
    plane.set_aspect("equal", adjustable="datalim")
    plane.legend(loc="best", fontsize=8)
    plane.set_title("states (2 std ellipses) and paths")
    times = np.arange(len(retrieved)) * sample_period
    for dimension, name in enumerate(signal_names):
        timeline.plot(times, retrieved[:, dimension], color=f"C{dimension}", lw=2, label=name)
    timeline.set_xlabel("time (s)")
    timeline.legend(loc="best", fontsize=8)
    timeline.set_title("signals over time (faint: demonstrations)")
    return figure
