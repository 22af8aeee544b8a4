"""Where the hand went: its paths among the spec's regions and the scene's objects, its
distance to each region over time, and its tilt."""

from __future__ import annotations

import numpy as np
from matplotlib import patheffects
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

import stl_lfd.rotations as rotations
from stl_lfd.report import objects
from stl_lfd.report.figures.base import BEST, INITIAL, FigureSpec, ReportOptions, best_in_words, numbered_in_words, per_trial, trial_colors
from stl_lfd.report.run_data import RunData, signed_distance
from stl_lfd.rotations import QUATERNION_COLUMNS

REGION_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink")
TURNING = np.radians(1.0)  # a hand tilted less than this throughout points down: nothing to show
VIEWS = (("x", "y"), ("x", "z"), ("y", "z"))  # from above, then from the side


class Trajectories(FigureSpec):
    """End-effector paths of every trial from above (x-y, true to scale) and from the side (x-z,
    y-z); the unoptimised skill dashed, the best in red, starts as circles and ends as squares;
    the spec's regions as labelled boxes; the scene's frame objects as grey outlines and the
    moving objects' paths (the shaft's) of the unoptimised and the best trial dotted."""

    name = "trajectories"

    def draw(self, run: RunData, options: ReportOptions) -> Figure:
        tables = {number: table for number, table in run.signals.items() if {"x", "y", "z"} <= set(table.columns)}
        limits = {axis: _limits(run, tables, axis) for axis in "xyz"}
        top_width = float(np.clip(7.0 * np.ptp(limits["x"]) / np.ptp(limits["y"]), 3.0, 8.0))
        figure = Figure(figsize=(top_width + 6.5, 7.5), layout="constrained")
        grid = figure.add_gridspec(2, 2, width_ratios=[top_width, 6.0])
        panels = [figure.add_subplot(grid[:, 0]), figure.add_subplot(grid[0, 1]), figure.add_subplot(grid[1, 1])]
        numbers = [trial.trial for trial in run.trials if trial.trial in tables]
        best = run.best.trial if run.best is not None and run.best.trial in tables else None
        carried = {0: (INITIAL, "unoptimised")} | ({best: (BEST, "best")} if best is not None else {})
        for axes, (across, up) in zip(panels, VIEWS):
            objects.draw_objects(axes, run, across, up)
            objects.draw_object_paths(axes, run, across, up, carried)
            _region_boxes(axes, run, across, up)
            for color, number in zip(trial_colors(len(numbers)), numbers):
                axes.plot(tables[number].columns[across], tables[number].columns[up], color=color, lw=1)
            if 0 in tables:
                _path_with_ends(axes, tables[0], across, up, INITIAL, 1.5, "--", "unoptimised")
            if best is not None:
                _path_with_ends(axes, tables[best], across, up, BEST, 2.2, "-", f"best (trial {best})")
            axes.set(xlim=limits[across], ylim=limits[up], xlabel=f"{across} (m)", ylabel=f"{up} (m)")
        panels[0].set(aspect="equal", title="from above (x-y, to scale)")
        panels[1].set_title("from the side (x-z)")
        panels[2].set_title("from the side (y-z)")
        if best is not None:
            for axes, (across, up) in zip(panels, VIEWS):
                _approach_axes(axes, tables[best], across, up)
        handles = [*panels[0].get_legend_handles_labels()[0], *_end_markers()]
        figure.legend(handles=handles, loc="outside lower center", ncols=len(handles), fontsize="small")
        figure.suptitle(f"{run.task.name}: end-effector paths of {len(numbers)} trials")
        return figure

    def caption(self, run: RunData) -> str:
        return (
            f"End-effector paths of every trial seen from above (x-y) and from the side (x-z, y-z): {numbered_in_words(run)}. "
            "Circles mark where the unoptimised and the best path start, squares where they end."
            + (" The coloured boxes are the regions the spec uses." if _drawn_regions(run) else "")
            + (" Black arrows: where the best trial's hand points (its approach axis), projected on each view." if _best_turns_the_hand(run) else "")
            + (
                " Grey: the objects the task is about (outlines of their bounding boxes); dotted, the path of the moved object's centre "
                "in the unoptimised and the best trial, its end as a cross."
                if objects.fixed_frame_objects(run) or objects.moving_frames(run)
                else ""
            )
        )


def _drawn_regions(run: RunData) -> bool:
    """Whether the trajectories figure draws a region: one that bounds two of x, y, z."""
    return any(len(set(box) & {"x", "y", "z"}) >= 2 for box in run.regions.values())


def _best_turns_the_hand(run: RunData) -> bool:
    table = run.signals.get(run.best.trial) if run.best is not None else None
    return table is not None and turns_the_hand(table)


def _limits(run: RunData, tables: dict, axis: str, margin: float = 0.06) -> tuple[float, float]:
    """The range of `axis` that holds every path and every region, with a margin."""
    values = [value for table in tables.values() for value in (np.min(table.columns[axis]), np.max(table.columns[axis]))]
    values += [bound for box in run.regions.values() if axis in box for bound in box[axis]]
    values += objects.object_extents(run, axis)
    for name in objects.moving_frames(run):
        values += [value for table in tables.values() for value in (np.min(table.columns[f"{name}_{axis}"]), np.max(table.columns[f"{name}_{axis}"]))]
    low, high = (min(values), max(values)) if values else (0.0, 1.0)
    pad = max(high - low, 0.02) * margin
    return low - pad, high + pad


def _region_boxes(axes, run: RunData, across: str, up: str) -> None:
    """The spec's regions that bound both coordinates of a view, as boxes with their names on
    top (one label for boxes that coincide in the view), drawn over the paths so that they can
    be read."""
    names_at: dict[tuple, list[str]] = {}
    colors: dict[tuple, str] = {}
    for index, (name, box) in enumerate(run.regions.items()):
        if across in box and up in box:
            corners = (*box[across], *box[up])
            names_at.setdefault(corners, []).append(name)
            colors.setdefault(corners, REGION_COLORS[index % len(REGION_COLORS)])
    for (x0, x1, y0, y1), names in names_at.items():
        color = colors[(x0, x1, y0, y1)]
        axes.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor=color, alpha=0.2, edgecolor="none"))
        axes.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, edgecolor=color, lw=1))
        outline = [patheffects.withStroke(linewidth=2.5, foreground="white")]
        axes.text(x0, y1, f"{', '.join(names)}", ha="left", va="bottom", fontsize=10, color=color, weight="bold", zorder=6, path_effects=outline)


def _path_with_ends(axes, table, across: str, up: str, color, width: float, style: str, label: str) -> None:
    x, y = table.columns[across], table.columns[up]
    axes.plot(x, y, color=color, lw=width, ls=style, label=label, zorder=4)
    axes.plot(x[:1], y[:1], marker="o", ms=8, color=color, mec="white", ls="none", zorder=5)
    axes.plot(x[-1:], y[-1:], marker="s", ms=8, color=color, mec="white", ls="none", zorder=5)


def _end_markers() -> list:
    from matplotlib.lines import Line2D

    return [Line2D([], [], marker="o", color="0.3", ls="none", label="start"), Line2D([], [], marker="s", color="0.3", ls="none", label="end")]


def turns_the_hand(table) -> bool:
    """Whether a recording turns the hand by a degree or more (and says how: quaternions), so
    that its approach axis is worth drawing."""
    return set(QUATERNION_COLUMNS) <= set(table.columns) and "tilt" in table.columns and bool(np.max(table.columns["tilt"]) >= TURNING)


def _approach_axes(axes, table, across: str = "x", up: str = "y", count: int = 12, length: float = 0.03) -> None:
    """Arrows along a path that turns the hand: its approach axis (the gripper's z) at `count`
    instants, projected on the view's plane (`across`, `up`)."""
    if not turns_the_hand(table):
        return
    at = np.linspace(0, table.samples - 1, count).astype(int)
    approach = rotations.to_matrix(np.column_stack([table.columns[name][at] for name in QUATERNION_COLUMNS]))[:, :, 2]
    columns = {"x": 0, "y": 1, "z": 2}
    u, v = approach[:, columns[across]], approach[:, columns[up]]
    x, y = table.columns[across][at], table.columns[up][at]
    axes.quiver(x, y, u, v, color="black", angles="xy", scale_units="xy", scale=1 / length, width=0.006, zorder=5, label="approach axis (best)")


class RegionDistances(FigureSpec):
    """Per region constraint of the spec: signed distance (negative inside) over its time window
    for every trial, the boundary at 0, the best trial in red."""

    name = "region_distances"
    left_out = "the spec names no fixed region (a box of constant x, y, z bounds) under F, G or G !"

    def applies(self, run: RunData, options: ReportOptions) -> bool:
        return bool(_region_constraints(run) and run.signals)

    def draw(self, run: RunData, options: ReportOptions) -> Figure:
        constraints = _region_constraints(run)
        figure = Figure(figsize=(5 * len(constraints), 3.8), layout="constrained")
        axes_list = np.atleast_1d(figure.subplots(1, len(constraints), squeeze=False)[0])
        numbers = [trial.trial for trial in run.trials if trial.trial in run.signals]
        best = run.best.trial if run.best is not None else None
        for axes, constraint in zip(axes_list, constraints):
            box = run.regions[constraint.region]
            for color, number in zip(trial_colors(len(numbers)), numbers):
                _plot_distance(axes, run.signals[number], box, constraint.interval, color, 1.0)
            if 0 in run.signals:
                _plot_distance(axes, run.signals[0], box, constraint.interval, INITIAL, 1.5, "--")
            if best in run.signals:
                _plot_distance(axes, run.signals[best], box, constraint.interval, BEST, 2.2)
            axes.axhline(0.0, color="k", lw=1)
            window = "whole trace" if constraint.interval is None else f"[{constraint.interval[0]:g}, {constraint.interval[1]:g}] s"
            axes.set(title=f"{constraint.kind} {constraint.region}, {window}", xlabel="t (s)", ylabel="signed distance (m), < 0 inside")
        return figure

    def caption(self, run: RunData) -> str:
        return (
            "Signed distance (m, negative inside) to each region the spec names, over the time window in which it applies: "
            "F R is met when the curve dips below 0 somewhere in its window, G R when it stays below 0 throughout, "
            f"G !R when it stays above 0; the unoptimised skill dashed, {best_in_words(run)}."
        )


def _region_constraints(run: RunData) -> list:
    return [constraint for constraint in run.constraints if constraint.region in run.regions]


def _plot_distance(axes, table, box, interval, color, width, style="-") -> None:
    times = table.times
    inside = np.ones_like(times, dtype=bool) if interval is None else (times >= interval[0] - 1e-9) & (times <= interval[1] + 1e-9)
    axes.plot(times[inside], signed_distance(table, box)[inside], color=color, lw=width, ls=style)


class Tilt(FigureSpec):
    """The hand's tilt (angle between its approach axis and straight down) over time for every
    trial, when some trial turned the hand by more than a degree."""

    name = "tilt"
    left_out = "no trial turned the hand by more than a degree"

    def applies(self, run: RunData, options: ReportOptions) -> bool:
        return any(np.max(table.columns["tilt"]) > TURNING for table in _tilt_tables(run).values())

    def draw(self, run: RunData, options: ReportOptions) -> Figure:
        tables = _tilt_tables(run)
        figure = Figure(figsize=(8, 4), layout="constrained")
        axes = figure.subplots()
        per_trial(axes, run, {number: (table.times, np.degrees(table.columns["tilt"])) for number, table in tables.items()})
        axes.set(xlabel="t (s)", ylabel="tilt (degrees from straight down)", title="the hand's tilt per trial")
        figure.legend(loc="outside right upper", fontsize="small")
        return figure

    def caption(self, run: RunData) -> str:
        return f"The hand's tilt (the angle between its approach axis and straight down) over time per trial: {numbered_in_words(run)}."


def _tilt_tables(run: RunData) -> dict:
    return {number: table for number, table in run.signals.items() if "tilt" in table.columns}
