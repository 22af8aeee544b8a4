"""How the robot followed its references, for a run that learned a tracking model."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from stl_lfd.report.figures.base import BEST, FigureSpec, ReportOptions
from stl_lfd.report.run_data import RunData


class Tracking(FigureSpec):
    """How the robot followed its references, for a run that learned it (`tracking.json`): the
    best trial's executed path against the plan and against the tracking model's prediction,
    per axis over time; and per trial, the RMS error of the plan and of the final model as
    predictions of what was executed."""

    name = "tracking"
    left_out = "the run learned no tracking model (its backend plays the plan back, it has several object placements, or its method is not plan)"

    def applies(self, run: RunData, options: ReportOptions) -> bool:
        return run.tracking is not None and run.best is not None and run.best.trial in run.signals

    def draw(self, run: RunData, options: ReportOptions) -> Figure:
        from stl_lfd.optim.objective import objective_for
        from stl_lfd.optim.tracking import execution_of

        _, objective = objective_for(run.task, run.models, execute=False)
        model = run.tracking.model
        numbers = [number for number in [0, *(trial.trial for trial in run.trials)] if number in run.signals]
        points = {0: run.space.initial, **{trial.trial: trial.x for trial in run.trials}}
        errors = {}
        for number in numbers:
            execution = execution_of(objective, run.space.apply(run.models, points[number]), run.signals[number])
            times, executed = execution.times, execution.positions
            planned = np.column_stack([np.interp(times, execution.reference_times, axis) for axis in execution.reference_positions.T])
            predicted = model.predict(execution.reference_times, execution.reference_positions, times)
            errors[number] = (_rms(planned - executed), _rms(predicted - executed))
            if number == run.best.trial:
                best = (times, executed, planned, predicted)
        figure = Figure(figsize=(12, 6.5), layout="constrained")
        grid = figure.add_gridspec(3, 2, width_ratios=[3, 2])
        times, executed, planned, predicted = best
        for axis, name in enumerate("xyz"):
            axes = figure.add_subplot(grid[axis, 0])
            axes.plot(times, planned[:, axis], color="0.6", lw=1.2, label="plan (the reference)")
            axes.plot(times, executed[:, axis], color=BEST, lw=2, label="executed")
            axes.plot(times, predicted[:, axis], color="k", lw=1, ls="--", label="predicted by the tracking model")
            axes.set_ylabel(f"{name} (m)")
            if axis == 0:
                axes.set_title(f"best trial ({run.best.trial}): executed, planned and predicted")
                axes.legend(loc="best", fontsize="small")
        axes.set_xlabel("t (s)")
        bars = figure.add_subplot(grid[:, 1])
        labels = ["init" if number == 0 else str(number) for number in numbers]
        positions = np.arange(len(numbers))
        bars.bar(positions - 0.2, [1000 * errors[number][0] for number in numbers], width=0.4, color="0.6", label="plan")
        bars.bar(positions + 0.2, [1000 * errors[number][1] for number in numbers], width=0.4, color="k", label="tracking model")
        bars.set_xticks(positions, labels, fontsize=7)
        bars.set(xlabel="trial", ylabel="RMS error of the prediction (mm)", title=f"predicting each execution ({model.kind_})")
        bars.legend(loc="best", fontsize="small")
        return figure

    def caption(self, run: RunData) -> str:
        return (
            "How the robot followed its references. Left: the best trial's executed path against its plan (the reference) and against "
            "the prediction of the tracking model learned from the executions, per axis. Right: for every trial, the RMS "
            "error of the plan and of that final model as predictions of what was executed (the model was fitted on the trials "
            f"{_trial_list(run)}, so most of these are in-sample; tracking.json holds its held-out error). "
            + (
                "Method plan scored its candidates by this prediction."
                if run.tracking is not None and run.tracking.used
                else "The robot followed its plans within 1 mm, so method plan scored the plans themselves."
            )
        )


def _trial_list(run: RunData) -> str:
    numbers = run.tracking.trials if run.tracking is not None else []
    return ", ".join("init" if number == 0 else str(number) for number in numbers)


def _rms(difference: np.ndarray) -> float:
    return float(np.sqrt(np.mean(difference**2)))
