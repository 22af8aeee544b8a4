"""How the robot followed its references, for a run that learned a tracking model."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from stl_lfd.report.figures.base import BEST, FigureSpec, ReportOptions
from stl_lfd.report.run_data import RunData


class Tracking(FigureSpec):
    """How the robot followed its references, as the run recorded it in `tracking.json`: the
    best of the trials its tracking model was fitted on, executed against the plan and against
    the model's prediction, per axis over time; and per trial, the RMS error of the plan and of
    the model as predictions of what was executed."""

    name = "tracking"
    left_out = (
        "the run learned no tracking model (its backend plays the plan back, it has several object placements, or its method is not plan), "
        "or recorded it before tracking.json held the errors"
    )

    def applies(self, run: RunData, options: ReportOptions) -> bool:
        return run.tracking is not None and run.tracking.best is not None and bool(run.tracking.errors)

    def draw(self, run: RunData, options: ReportOptions) -> Figure:
        record = run.tracking
        number, paths = record.best
        figure = Figure(figsize=(12, 6.5), layout="constrained")
        grid = figure.add_gridspec(3, 2, width_ratios=[3, 2])
        for axis, name in enumerate("xyz"):
            axes = figure.add_subplot(grid[axis, 0])
            axes.plot(paths.times, paths.planned[:, axis], color="0.6", lw=1.2, label="plan (the reference)")
            axes.plot(paths.times, paths.executed[:, axis], color=BEST, lw=2, label="executed")
            axes.plot(paths.times, paths.predicted[:, axis], color="k", lw=1, ls="--", label="predicted by the tracking model")
            axes.set_ylabel(f"{name} (m)")
            if axis == 0:
                axes.set_title(f"{_trial_name(number)}: executed, planned and predicted")
                axes.legend(loc="best", fontsize="small")
        axes.set_xlabel("t (s)")
        bars = figure.add_subplot(grid[:, 1])
        numbers = sorted(record.errors)
        positions = np.arange(len(numbers))
        bars.bar(positions - 0.2, [1000 * record.errors[number][0] for number in numbers], width=0.4, color="0.6", label="plan")
        bars.bar(positions + 0.2, [1000 * record.errors[number][1] for number in numbers], width=0.4, color="k", label="tracking model")
        bars.set_xticks(positions, ["init" if number == 0 else str(number) for number in numbers], fontsize=7)
        bars.set(xlabel="trial", ylabel="RMS error of the prediction (mm)", title=f"predicting each execution ({record.model.kind_})")
        bars.legend(loc="best", fontsize="small")
        return figure

    def caption(self, run: RunData) -> str:
        return (
            "How the robot followed its references. Left: the best execution the tracking model was fitted on, against its plan (the reference) and against "
            "the model's prediction, per axis. Right: for every trial it was fitted on, the RMS "
            "error of the plan and of the model as predictions of what was executed (the model was fitted on the trials "
            f"{_trial_list(run)}, so these are in-sample; tracking.json holds its held-out error). "
            + (
                "Method plan scored its candidates by this prediction."
                if run.tracking is not None and run.tracking.used
                else "The robot followed its plans within 1 mm, so method plan scored the plans themselves."
            )
        )


def _trial_name(number: int) -> str:
    return "the unoptimised skill" if number == 0 else f"trial {number}"


def _trial_list(run: RunData) -> str:
    numbers = run.tracking.trials if run.tracking is not None else []
    return ", ".join("init" if number == 0 else str(number) for number in numbers)
