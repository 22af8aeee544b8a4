"""The figures of an optimisation run (the paper's plots). Each function takes a loaded run and
returns a matplotlib Figure, or None when the run lacks the data for it."""

from __future__ import annotations

import numpy as np
from matplotlib import patheffects
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure
from matplotlib.patches import FancyArrowPatch, Rectangle

import stl_lfd.rotations as rotations
from stl_lfd.hsmm import HSMM
from stl_lfd.report import objects
from stl_lfd.report.run_data import RunData, signed_distance
from stl_lfd.rotations import QUATERNION_COLUMNS

BEST = "tab:red"
INITIAL = "0.2"
REGION_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink")
TURNING = np.radians(1.0)  # a hand tilted less than this throughout points down: nothing to show


def _trial_colors(count: int) -> list[tuple]:
    """Light to dark grey-blue in trial order."""
    return [to_rgba("tab:blue", alpha=0.15 + 0.6 * index / max(count - 1, 1)) for index in range(count)]


VIEWS = (("x", "y"), ("x", "z"), ("y", "z"))  # from above, then from the side


def trajectories(run: RunData) -> Figure:
    """End-effector paths of every trial from above (x-y, true to scale) and from the side (x-z,
    y-z); the unoptimised skill dashed, the best in red, starts as circles and ends as squares;
    the spec's regions as labelled boxes; the scene's frame objects as grey outlines and the
    moving objects' paths (the shaft's) of the unoptimised and the best trial dotted."""
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
        for color, number in zip(_trial_colors(len(numbers)), numbers):
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


def tilt(run: RunData) -> Figure | None:
    """The hand's tilt (angle between its approach axis and straight down) over time for every
    trial, when some trial turned the hand by more than a degree."""
    tables = {number: table for number, table in run.signals.items() if "tilt" in table.columns}
    if not tables or not any(np.max(table.columns["tilt"]) > TURNING for table in tables.values()):
        return None
    figure = Figure(figsize=(8, 4), layout="constrained")
    axes = figure.subplots()
    _per_trial(axes, run, {number: (table.times, np.degrees(table.columns["tilt"])) for number, table in tables.items()})
    axes.set(xlabel="t (s)", ylabel="tilt (degrees from straight down)", title="the hand's tilt per trial")
    figure.legend(loc="outside right upper", fontsize="small")
    return figure


def _per_trial(axes, run: RunData, curves: dict[int, tuple[np.ndarray, np.ndarray]]) -> None:
    """Each trial's curve (trial number -> times, values; 0 the unoptimised skill) in its
    colour, the unoptimised one dashed and the best one in red, both labelled."""
    numbers = [number for number in curves if number > 0]
    for color, number in zip(_trial_colors(len(numbers)), numbers):
        axes.plot(*curves[number], color=color, lw=1)
    if 0 in curves:
        axes.plot(*curves[0], color=INITIAL, ls="--", label="unoptimised")
    if run.best is not None and run.best.trial in curves:
        axes.plot(*curves[run.best.trial], color=BEST, lw=2, label="best")


def region_distances(run: RunData) -> Figure | None:
    """Per region constraint of the spec: signed distance (negative inside) over its time window
    for every trial, the boundary at 0, the best trial in red."""
    constraints = [c for c in run.constraints if c.region in run.regions]
    if not constraints or not run.signals:
        return None
    figure = Figure(figsize=(5 * len(constraints), 3.8), layout="constrained")
    axes_list = np.atleast_1d(figure.subplots(1, len(constraints), squeeze=False)[0])
    numbers = [trial.trial for trial in run.trials if trial.trial in run.signals]
    best = run.best.trial if run.best is not None else None
    for axes, constraint in zip(axes_list, constraints):
        box = run.regions[constraint.region]
        for color, number in zip(_trial_colors(len(numbers)), numbers):
            _plot_distance(axes, run.signals[number], box, constraint.interval, color, 1.0)
        if 0 in run.signals:
            _plot_distance(axes, run.signals[0], box, constraint.interval, INITIAL, 1.5, "--")
        if best in run.signals:
            _plot_distance(axes, run.signals[best], box, constraint.interval, BEST, 2.2)
        axes.axhline(0.0, color="k", lw=1)
        window = "whole trace" if constraint.interval is None else f"[{constraint.interval[0]:g}, {constraint.interval[1]:g}] s"
        axes.set(title=f"{constraint.kind} {constraint.region}, {window}", xlabel="t (s)", ylabel="signed distance (m), < 0 inside")
    return figure


def _plot_distance(axes, table, box, interval, color, width, style="-") -> None:
    times = table.times
    inside = np.ones_like(times, dtype=bool) if interval is None else (times >= interval[0] - 1e-9) & (times <= interval[1] + 1e-9)
    axes.plot(times[inside], signed_distance(table, box)[inside], color=color, lw=width, ls=style)


def robustness_per_trial(run: RunData) -> Figure:
    """Robustness of each trial and the best so far; Sobol trials distinguished from the rest."""
    figure = Figure(figsize=(9, 4), layout="constrained")
    axes = figure.subplots()
    _robustness_curves(axes, run, label_prefix="")
    axes.axhline(0.0, color="k", lw=1)
    axes.axhline(run.summary.initial_robustness, color=INITIAL, ls="--", lw=1, label="unoptimised")
    axes.set(xlabel="trial", ylabel=f"{run.task.semantics} robustness", title=f"{run.task.name}: robustness per trial")
    figure.legend(loc="outside right upper", fontsize="small")
    return figure


def component_robustness(run: RunData) -> Figure | None:
    """Robustness of each top-level part of the spec per trial, each on its own scale (parts
    measured in metres and in newtons side by side would flatten one another), under the spec's
    robustness they compose to with the lowest part circled; None for runs recorded without
    parts. Beyond MAX_PANELS parts (many placements), all on one panel."""
    trials = [trial for trial in run.trials if trial.components]
    if not trials:
        return None
    names = list(trials[0].components)
    numbers = np.array([trial.trial for trial in trials])
    values = np.array([[trial.components.get(name, np.nan) for name in names] for trial in trials], dtype=float)  # n x parts
    lowest = np.nanmin(values, axis=1)
    separate = len(names) <= MAX_PANELS
    rows = 1 + len(names) if separate else 1
    figure = Figure(figsize=(10, 1.8 + 1.4 * rows), layout="constrained")
    panels = np.atleast_1d(figure.subplots(rows, 1, sharex=True, squeeze=False)[:, 0])
    top = panels[0]
    top.plot(numbers, [trial.robustness for trial in trials], color="k", lw=2, label=f"spec ({COMPOSED[run.task.semantics]})")
    top.scatter(numbers, lowest, s=50, facecolors="none", edgecolors="k", zorder=3, label="lowest part")
    for index, name in enumerate(names):
        axes = panels[1 + index] if separate else top
        axes.plot(numbers, values[:, index], marker="o", ms=3, lw=1, color=f"C{index % 10}", label=name)
        if separate:
            binding = values[:, index] == lowest
            axes.scatter(numbers[binding], values[binding, index], s=50, facecolors="none", edgecolors="k", zorder=3)
            axes.set_ylabel(_wrapped(name), fontsize="small")
    for axes in panels:
        axes.axhline(0.0, color="k", lw=0.8, ls=":")
    top.set(ylabel=f"{run.task.semantics} robustness", title=f"{run.task.name}: the spec's robustness and each of its parts (circled: the lowest)")
    panels[-1].set_xlabel("trial")
    top.legend(loc="best", fontsize="small")
    return figure


MAX_PANELS = 8


def _wrapped(text: str, width: int = 22) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(text, width)) or text


# How the spec's value is composed of its parts, as the components figure's legend says it.
COMPOSED = {"classic": "the minimum of the parts", "new": "the parts' new conjunction"}


def _robustness_curves(axes, run: RunData, label_prefix: str, color: str = "tab:blue") -> None:
    numbers = np.array([trial.trial for trial in run.trials], dtype=int)
    values = np.array([trial.robustness if trial.robustness is not None else np.nan for trial in run.trials], dtype=float)
    initial = np.array([trial.phase in ("sobol", "design") for trial in run.trials], dtype=bool)
    best_so_far = np.fmax.accumulate(np.where(np.isnan(values), -np.inf, values))
    if not label_prefix:
        axes.scatter(
            numbers[initial],
            values[initial],
            marker="s",
            color="0.5",
            label=f"initial ({run.task.optimizer.initial_choice})",
            zorder=3,
        )
        axes.scatter(numbers[~initial], values[~initial], marker="o", color=color, label=f"{run.task.optimizer.method} trials", zorder=3)
    axes.step(numbers, np.where(np.isfinite(best_so_far), best_so_far, np.nan), where="post", color=color, lw=2, label=f"{label_prefix}best so far")


def compare_runs(runs: list[RunData]) -> Figure:
    """Best-so-far robustness of several runs on one plot."""
    figure = Figure(figsize=(7.5, 4), layout="constrained")
    axes = figure.subplots()
    for index, run in enumerate(runs):
        label = f"{run.path.name} ({run.task.optimizer.method}, {run.task.semantics}): "
        _robustness_curves(axes, run, label_prefix=label, color=f"C{index}")
    axes.axhline(0.0, color="k", lw=1)
    axes.set(xlabel="trial", ylabel="robustness", title="best so far")
    axes.legend(loc="lower right", fontsize=8)
    return figure


def gp_slices(run: RunData, parameters: list[str] | None = None) -> Figure | None:
    """GP mean and 95 % band along one or two parameters through the best point, with the
    observations (projected). Default parameters: the two with the shortest GP lengthscales."""
    X, Y = run.observations()
    if len(Y) < 3 or run.best is None:
        return None
    import torch

    from stl_lfd.optim.methods.gp import fit_gp

    bounds = run.space.bounds
    model = fit_gp(X, Y, bounds)
    names = list(run.space.names)
    chosen = parameters or _most_relevant(model, names, 2)
    figure = Figure(figsize=(5.5 * len(chosen), 4), layout="constrained")
    axes_list = np.atleast_1d(figure.subplots(1, len(chosen), squeeze=False)[0])
    for axes, name in zip(axes_list, chosen):
        index = names.index(name)
        grid = np.linspace(bounds[0, index], bounds[1, index], 200)
        points = np.repeat(run.best.x[None], grid.size, axis=0)
        points[:, index] = grid
        with torch.no_grad():
            posterior = model.posterior(torch.as_tensor(points, dtype=torch.float64))
            mean = posterior.mean.numpy().ravel()
            std = posterior.variance.clamp_min(0).sqrt().numpy().ravel()
        axes.fill_between(grid, mean - 1.96 * std, mean + 1.96 * std, color="tab:blue", alpha=0.2, label="95 % band")
        axes.plot(grid, mean, color="tab:blue", label="GP mean")
        axes.scatter(X[:, index], Y, color="k", s=12, label="trials")
        axes.axvline(run.best.x[index], color=BEST, lw=1, label="best")
        axes.axhline(0.0, color="k", lw=0.8)
        axes.set(xlabel=name, ylabel="robustness", title=f"through the best point: {name}")
        axes.tick_params(axis="x", labelrotation=30)
    axes_list[0].legend(loc="best", fontsize=8)
    return figure


def _most_relevant(model, names: list[str], count: int) -> list[str]:
    kernel = getattr(model.covar_module, "base_kernel", model.covar_module)
    lengthscales = kernel.lengthscale.detach().numpy().ravel() if getattr(kernel, "lengthscale", None) is not None else None
    if lengthscales is None or lengthscales.size != len(names):
        return names[:count]
    return [names[index] for index in np.argsort(lengthscales)[:count]]


def transition_graphs(run: RunData) -> Figure | None:
    """The states and transitions before and after optimisation of each skill whose transitions
    are optimised (None when none is): edge width by probability, the state sequence followed
    by the retrieval highlighted."""
    skills = [skill for skill, part in run.space.parts.items() if part.transition_slots]
    if not skills:
        return None
    figure = Figure(figsize=(12, 3.6 * len(skills)), layout="constrained")
    rows = figure.subplots(len(skills), 2, squeeze=False)
    best_models = run.best_models()
    for (before, after), skill in zip(rows, skills):
        prefix = "" if len(skills) == 1 else f"{skill}, "
        _transition_graph(before, run.models[skill], f"{prefix}unoptimised")
        _transition_graph(after, best_models[skill], f"{prefix}best (trial {run.best.trial})" if run.best else f"{prefix}best")
    return figure


def _transition_graph(axes, model: HSMM, title: str) -> None:
    K = model.n_states
    transmat = model.normalized_transmat()
    followed = followed_states(model)
    used = set(zip(followed[:-1], followed[1:]))
    positions = {state: (state, 0.0) for state in range(K)}
    for source in range(K):
        for target in range(K):
            probability = transmat[source, target]
            if probability < 0.01:
                continue
            highlighted = (source, target) in used
            bend = 0.35 if target > source else -0.35
            axes.add_patch(
                FancyArrowPatch(
                    positions[source],
                    positions[target],
                    connectionstyle=f"arc3,rad={-bend}",
                    arrowstyle="-|>",
                    mutation_scale=12,
                    lw=0.5 + 5 * probability,
                    color=BEST if highlighted else "0.55",
                    shrinkA=14,
                    shrinkB=14,
                    alpha=0.9,
                )
            )
    for state, (x, y) in positions.items():
        face = "mistyrose" if state in followed else "white"
        axes.scatter([x], [y], s=700, color=face, edgecolor="k", zorder=3)
        axes.text(x, y, str(state + 1), ha="center", va="center", zorder=4)
        axes.text(x, -0.42, f"{model.duration_means_[state]:.1f} s", ha="center", fontsize=8)
    axes.set(xlim=(-0.7, K - 0.3), ylim=(-0.6, 0.6), title=f"{title}: states followed {' → '.join(str(s + 1) for s in followed)}")
    axes.axis("off")


def followed_states(model: HSMM) -> list[int]:
    """The states (0-based) the retrieval of `model` goes through, in order."""
    states = model.state_sequence(int(round((model.expected_duration() + 1.0) / model.sample_period_)) + 1)  # no tracking needed (nor frame poses)
    changes = np.flatnonzero(np.diff(states)) + 1
    return [int(states[0])] + [int(states[index]) for index in changes]


def durations_per_trial(run: RunData) -> Figure | None:
    """Duration means of the states each trial's retrieval follows, stacked in the order it
    follows them (the skill's timeline per trial); one panel per skill whose durations are
    optimised, None when none is."""
    skills = [skill for skill, part in run.space.parts.items() if part.duration_slots]
    if not skills:
        return None
    figure = Figure(figsize=(9, 4 * len(skills)), layout="constrained")
    for axes, skill in zip(np.atleast_1d(figure.subplots(len(skills), 1, squeeze=False)[:, 0]), skills):
        _duration_bars(axes, run, skill)
    return figure


def _duration_bars(axes, run: RunData, skill: str) -> None:
    labels = ["init"] + [str(trial.trial) for trial in run.trials]
    models = [run.models[skill]] + [run.space.apply(run.models, trial.x)[skill] for trial in run.trials]
    bottom = np.zeros(len(models))
    labelled = set()
    for position, model in enumerate(models):
        for state in followed_states(model):
            label = f"state {state + 1}" if state not in labelled else None
            labelled.add(state)
            axes.bar(labels[position], model.duration_means_[state], bottom=bottom[position], color=f"C{state % 10}", label=label, width=0.8)
            bottom[position] += model.duration_means_[state]
    if len(run.models) == 1:
        axes.axhline(run.task.duration, color="k", ls="--", lw=1, label="rollout ends")
    if run.best is not None:
        axes.get_xticklabels()[labels.index(str(run.best.trial))].set_color(BEST)
    title = "duration means per state" + ("" if len(run.models) == 1 else f" ({skill})")
    axes.set(xlabel="trial (best in red)", ylabel="duration mean (s)", title=title)
    axes.tick_params(axis="x", labelsize=7)
    axes.legend(loc="upper left", bbox_to_anchor=(1, 1), fontsize=8)


def contact_forces(run: RunData) -> Figure | None:
    """Contact force over time of every trial, when some trial recorded a non-zero force."""
    tables = {number: table for number, table in run.signals.items() if "force" in table.columns}
    if not tables or not any(np.any(table.columns["force"] > 0) for table in tables.values()):
        return None
    figure = Figure(figsize=(8, 4), layout="constrained")
    axes = figure.subplots()
    _per_trial(axes, run, {number: (table.times, table.columns["force"]) for number, table in tables.items()})
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


def wrench(run: RunData) -> Figure | None:
    """The wrist sensor's force and torque components (`fx`..`tz`, base frame) of the
    unoptimised and the best trial, when they were recorded and something was touched."""
    from stl_lfd.choices import WRENCH_SIGNALS

    shown = {number: run.signals[number] for number in (0, run.best.trial if run.best is not None else None) if number in run.signals}
    shown = {number: table for number, table in shown.items() if set(WRENCH_SIGNALS) <= set(table.columns)}
    if not shown or not any(np.any(table.columns["force"] > 0) for table in shown.values() if "force" in table.columns):
        return None
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


def object_signals(run: RunData) -> Figure | None:
    """The scene objects' signals the spec constrains (shaft tilt, depth, offset...) per trial,
    with the spec's thresholds."""
    return objects.object_signals(run, _per_trial)


def tracking(run: RunData) -> Figure | None:
    """How the robot followed its references, for a run that learned it (`tracking.json`): the
    best trial's executed path against the plan and against the tracking model's prediction,
    per axis over time; and per trial, the RMS error of the plan and of the final model as
    predictions of what was executed."""
    if run.tracking is None or run.best is None or run.best.trial not in run.signals:
        return None
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


def _rms(difference: np.ndarray) -> float:
    return float(np.sqrt(np.mean(difference**2)))
