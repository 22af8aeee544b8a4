"""What was touched: the contact force, the wrist sensor's components, and the signals of the
scene's objects that the spec constrains."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from stl_lfd.choices import WRENCH_SIGNALS
from stl_lfd.report import objects
from stl_lfd.report.figures.base import FigureSpec, ReportOptions, numbered_in_words, per_trial
from stl_lfd.report.run_data import RunData


class Forces(FigureSpec):
    """Contact force over time of every trial, when some trial recorded a non-zero force."""

    name = "forces"
    left_out = "no trial touched anything (the contact force was zero throughout)"

    def applies(self, run: RunData, options: ReportOptions) -> bool:
        return any(np.any(table.columns["force"] > 0) for table in _force_tables(run).values())

    def draw(self, run: RunData, options: ReportOptions) -> Figure:
        tables = _force_tables(run)
        figure = Figure(figsize=(8, 4), layout="constrained")
        axes = figure.subplots()
        per_trial(axes, run, {number: (table.times, table.columns["force"]) for number, table in tables.items()})
        title = "contact force per trial"
        shown = [tables[number].columns["force"] for number in (0, run.best.trial if run.best is not None else None) if number in tables]
        highest = max((float(np.max(force)) for force in shown), default=0.0)
        if highest > 0 and max(float(np.max(table.columns["force"])) for table in tables.values()) > 2.0 * highest:
            axes.set_ylim(-0.05 * highest, 1.5 * highest)  # other trials' collisions would flatten the two that matter
            title += " (other trials' peaks cut off)"
        objects.draw_thresholds(axes, run.thresholds.get("force", []))
        axes.set(xlabel="t (s)", ylabel="contact force (N)", title=title)
        axes.legend(loc="best")
        return figure

    def caption(self, run: RunData) -> str:
        return f"Contact force over time per trial: {numbered_in_words(run)}." + (
            " Dashed green: the spec's thresholds on it." if run.thresholds.get("force") else ""
        )


def _force_tables(run: RunData) -> dict:
    return {number: table for number, table in run.signals.items() if "force" in table.columns}


class Wrench(FigureSpec):
    """The wrist sensor's force and torque components (`fx`..`tz`, base frame) of the
    unoptimised and the best trial, when they were recorded and something was touched."""

    name = "wrench"
    left_out = "the run recorded no wrist force-torque components, or nothing was touched"

    def applies(self, run: RunData, options: ReportOptions) -> bool:
        return any(np.any(table.columns["force"] > 0) for table in _wrench_tables(run).values() if "force" in table.columns)

    def draw(self, run: RunData, options: ReportOptions) -> Figure:
        shown = _wrench_tables(run)
        figure = Figure(figsize=(9, 5.5), layout="constrained")
        panels = figure.subplots(2, 1, sharex=True)
        styles = {0: ("--", "unoptimised"), run.best.trial if run.best is not None else -1: ("-", "best")}
        for axes, names, unit in ((panels[0], WRENCH_SIGNALS[:3], "N"), (panels[1], WRENCH_SIGNALS[3:], "Nm")):
            for color, name in zip(("tab:red", "tab:green", "tab:blue"), names):
                for number, table in shown.items():
                    style, label = styles[number]
                    axes.plot(table.times, table.columns[name], color=color, ls=style, lw=1.2, label=f"{name}, {label}")
            axes.set_ylabel(f"{'force' if unit == 'N' else 'torque'} ({unit})")
            axes.legend(loc="upper left", bbox_to_anchor=(1, 1), fontsize=8)
        panels[-1].set_xlabel("t (s)")
        figure.suptitle("the wrist's force and torque, base frame (the hand's and its load's weight removed)")
        return figure

    def caption(self, run: RunData) -> str:
        return (
            "The wrist force-torque sensor's components of the unoptimised skill (dashed) and the best trial (solid), in the robot's base "
            "frame with the hand's and its load's weight removed, as a Franka's external-wrench estimate gives them: force (N) above, "
            "torque about the grasp point (Nm) below."
        )


def _wrench_tables(run: RunData) -> dict:
    """The unoptimised and the best trial's recordings, where they hold the wrench's components."""
    shown = {number: run.signals[number] for number in (0, run.best.trial if run.best is not None else None) if number in run.signals}
    return {number: table for number, table in shown.items() if set(WRENCH_SIGNALS) <= set(table.columns)}


class ObjectSignals(FigureSpec):
    """The scene objects' signals the spec constrains (shaft tilt, depth, offset...) per trial,
    with the spec's thresholds."""

    name = "objects"
    left_out = "the spec compares no recorded signal of the scene's objects (shaft_tilt, shaft_depth, ...) with a number"

    def applies(self, run: RunData, options: ReportOptions) -> bool:
        return bool(objects.constrained_object_signals(run) or objects.constrained_object_expressions(run))

    def draw(self, run: RunData, options: ReportOptions) -> Figure:
        return objects.object_signals(run, per_trial)

    def caption(self, run: RunData) -> str:
        words = [objects.signal_in_words(signal, run.scene) for signal in objects.constrained_object_signals(run)]
        shown = "; ".join(words + objects.constrained_object_expressions(run))
        return (
            f"The signals of the scene's objects that the spec constrains, over time per trial: {numbered_in_words(run)}; dashed green, the spec's "
            f"thresholds. Shown: {shown}."
        )
