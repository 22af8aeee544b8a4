"""The figures of an optimisation run (the paper's plots). Each function takes a loaded run and
returns a matplotlib Figure, or None when the run lacks the data for it."""

from __future__ import annotations

import numpy as np
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure
from matplotlib.patches import FancyArrowPatch, Rectangle

import stl_lfd.rotations as rotations
from stl_lfd.hsmm import HSMM
from stl_lfd.report.run_data import RunData, signed_distance
from stl_lfd.rotations import QUATERNION_COLUMNS

BEST = "tab:red"
INITIAL = "0.2"
REGION_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink")
TURNING = np.radians(1.0)  # a hand tilted less than this throughout points down: nothing to show


def _trial_colors(count: int) -> list[tuple]:
    """Light to dark grey-blue in trial order."""
    return [to_rgba("tab:blue", alpha=0.15 + 0.6 * index / max(count - 1, 1)) for index in range(count)]


def trajectories(run: RunData) -> Figure:
    """End-effector paths of every trial on the x-y plane; best in red; regions as patches."""
    figure = Figure(figsize=(6.5, 6), layout="constrained")
    axes = figure.subplots()
    for index, (name, box) in enumerate(run.regions.items()):
        if "x" in box and "y" in box:
            (x0, x1), (y0, y1) = box["x"], box["y"]
            color = REGION_COLORS[index % len(REGION_COLORS)]
            axes.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, color=color, alpha=0.25, lw=0))
            axes.text((x0 + x1) / 2, (y0 + y1) / 2, name, ha="center", va="center", fontsize=11, color=color, weight="bold")
    numbers = [trial.trial for trial in run.trials if trial.trial in run.signals]
    for color, number in zip(_trial_colors(len(numbers)), numbers):
        table = run.signals[number]
        axes.plot(table.columns["x"], table.columns["y"], color=color, lw=1)
    if 0 in run.signals:
        axes.plot(run.signals[0].columns["x"], run.signals[0].columns["y"], color=INITIAL, lw=1.5, ls="--", label="unoptimised")
    if run.best is not None and run.best.trial in run.signals:
        best = run.signals[run.best.trial]
        axes.plot(best.columns["x"], best.columns["y"], color=BEST, lw=2.2, label=f"best (trial {run.best.trial})")
        _approach_axes(axes, best)
    axes.set(xlabel="x (m)", ylabel="y (m)", title=f"{run.task.name}: end-effector paths of {len(numbers)} trials", aspect="equal")
    axes.legend(loc="best")
    return figure


def _approach_axes(axes, table, count: int = 12, length: float = 0.03) -> None:
    """Arrows along a path that turns the hand: its approach axis (the gripper's z) at `count`
    instants, projected on the x-y plane."""
    if not set(QUATERNION_COLUMNS) <= set(table.columns) or "tilt" not in table.columns or np.max(table.columns["tilt"]) < TURNING:
        return
    at = np.linspace(0, table.samples - 1, count).astype(int)
    approach = rotations.to_matrix(np.column_stack([table.columns[name][at] for name in QUATERNION_COLUMNS]))[:, :, 2]
    x, y = table.columns["x"][at], table.columns["y"][at]
    axes.quiver(x, y, approach[:, 0], approach[:, 1], color="black", angles="xy", scale_units="xy", scale=1 / length, width=0.006, label="approach axis (best)")


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
    axes.legend(loc="best")
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
        if best in run.signals:
            _plot_distance(axes, run.signals[best], box, constraint.interval, BEST, 2.2)
        axes.axhline(0.0, color="k", lw=1)
        window = "whole trace" if constraint.interval is None else f"[{constraint.interval[0]:g}, {constraint.interval[1]:g}] s"
        axes.set(title=f"{constraint.kind} {constraint.region}, {window}", xlabel="t (s)", ylabel="signed distance (m), < 0 inside")
    return figure


def _plot_distance(axes, table, box, interval, color, width) -> None:
    times = table.times
    inside = np.ones_like(times, dtype=bool) if interval is None else (times >= interval[0] - 1e-9) & (times <= interval[1] + 1e-9)
    axes.plot(times[inside], signed_distance(table, box)[inside], color=color, lw=width)


def robustness_per_trial(run: RunData) -> Figure:
    """Robustness of each trial and the best so far; Sobol trials distinguished from the rest."""
    figure = Figure(figsize=(7.5, 4), layout="constrained")
    axes = figure.subplots()
    _robustness_curves(axes, run, label_prefix="")
    axes.axhline(0.0, color="k", lw=1)
    axes.axhline(run.summary.initial_robustness, color=INITIAL, ls="--", lw=1, label="unoptimised")
    axes.set(xlabel="trial", ylabel=f"{run.task.semantics} robustness", title=f"{run.task.name}: robustness per trial")
    axes.legend(loc="lower right")
    return figure


def component_robustness(run: RunData) -> Figure | None:
    """Robustness of each top-level part of the spec per trial (which part binds, trial by
    trial), with the spec's robustness they compose to; None for runs recorded without parts."""
    trials = [trial for trial in run.trials if trial.components]
    if not trials:
        return None
    names = list(trials[0].components)
    figure = Figure(figsize=(7.5, 4), layout="constrained")
    axes = figure.subplots()
    numbers = np.array([trial.trial for trial in trials])
    for index, name in enumerate(names):
        values = np.array([trial.components.get(name, np.nan) for trial in trials], dtype=float)
        axes.plot(numbers, values, marker="o", ms=3, lw=1, color=f"C{index}", label=name)
    axes.plot(numbers, [trial.robustness for trial in trials], color="k", lw=2, label="spec (composed)")
    binding = np.array([min(trial.components.values()) for trial in trials])
    axes.scatter(numbers, binding, s=60, facecolors="none", edgecolors="k", zorder=3, label="binding part")
    axes.axhline(0.0, color="k", lw=0.8, ls=":")
    axes.set(xlabel="trial", ylabel=f"{run.task.semantics} robustness", title=f"{run.task.name}: robustness of each part of the spec")
    axes.legend(loc="lower right", fontsize="small")
    return figure


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
            label="initial (Sobol)" if run.task.optimizer.method != "plan" else "initial (design)",
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
        axes.set(xlabel=name, ylabel="robustness", title=f"GP slice through the best point: {name}")
    axes_list[0].legend(loc="best", fontsize=8)
    return figure


def _most_relevant(model, names: list[str], count: int) -> list[str]:
    kernel = getattr(model.covar_module, "base_kernel", model.covar_module)
    lengthscales = kernel.lengthscale.detach().numpy().ravel() if getattr(kernel, "lengthscale", None) is not None else None
    if lengthscales is None or lengthscales.size != len(names):
        return names[:count]
    return [names[index] for index in np.argsort(lengthscales)[:count]]


def transition_graphs(run: RunData) -> Figure:
    """The skill's states and transitions before and after optimisation: edge width by
    probability, the state sequence followed by the retrieval highlighted."""
    skills = list(run.models)
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


def durations_per_trial(run: RunData) -> Figure:
    """Duration means of each state per trial, stacked (the skill's timeline per trial); one
    panel per skill whose durations are optimised."""
    skills = [skill for skill, part in run.space.parts.items() if part.duration_slots] or list(run.models)[:1]
    figure = Figure(figsize=(9, 4 * len(skills)), layout="constrained")
    for axes, skill in zip(np.atleast_1d(figure.subplots(len(skills), 1, squeeze=False)[:, 0]), skills):
        _duration_bars(axes, run, skill)
    return figure


def _duration_bars(axes, run: RunData, skill: str) -> None:
    labels = ["init"] + [str(trial.trial) for trial in run.trials]
    models = [run.models[skill]] + [run.space.apply(run.models, trial.x)[skill] for trial in run.trials]
    durations = np.array([model.duration_means_ for model in models])
    bottom = np.zeros(len(models))
    for state in range(durations.shape[1]):
        axes.bar(labels, durations[:, state], bottom=bottom, color=f"C{state}", label=f"state {state + 1}", width=0.8)
        bottom += durations[:, state]
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
    axes.set(xlabel="t (s)", ylabel="contact force (N)", title=title)
    axes.legend(loc="best")
    return figure
