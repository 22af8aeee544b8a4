"""How good the trials were: the robustness per trial, per part of the spec, against other
runs, and what a GP of the trials says along the most relevant parameters."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from stl_lfd.optim.trials import best_so_far, robustness_of
from stl_lfd.report.explain import semantics_in_words
from stl_lfd.report.figures.base import BEST, INITIAL, FigureSpec, ReportOptions
from stl_lfd.report.run_data import RunData
from stl_lfd.report.surrogate import Surrogate
from stl_lfd.spelling import spelled

MAX_PANELS = 8  # parts of a spec drawn on panels of their own; beyond, all on one
# How the spec's value is composed of its parts, as the components figure's legend says it.
COMPOSED = {"classic": "the minimum of the parts", "new": "the parts' new conjunction"}


class Robustness(FigureSpec):
    """Robustness of each trial and the best so far; the initial trials distinguished from the rest."""

    name = "robustness"

    def draw(self, run: RunData, options: ReportOptions) -> Figure:
        figure = Figure(figsize=(9, 4), layout="constrained")
        axes = figure.subplots()
        _robustness_curves(axes, run, label_prefix="")
        axes.axhline(0.0, color="k", lw=1)
        axes.axhline(run.summary.initial_robustness, color=INITIAL, ls="--", lw=1, label="unoptimised")
        axes.set(xlabel="trial", ylabel=f"{run.task.semantics} robustness", title=f"{run.task.name}: robustness per trial")
        figure.legend(loc="outside right upper", fontsize="small")
        return figure

    def caption(self, run: RunData) -> str:
        optimizer = run.task.optimizer
        return (
            f"The {semantics_in_words(run)} of each trial, the value the optimiser maximises (above 0 satisfies the spec): "
            f"the first {optimizer.initial} trials ({optimizer.initial_choice}) as squares, "
            f"then those of method {optimizer.method} as circles; the line is the best so far, the dashed line the unoptimised skill."
        )


class Components(FigureSpec):
    """Robustness of each top-level part of the spec per trial, each on its own scale (parts
    measured in metres and in newtons side by side would flatten one another), under the spec's
    robustness they compose to with the lowest part circled. Beyond MAX_PANELS parts (many
    placements), all on one panel."""

    name = "components"
    left_out = "the run recorded no robustness per part of the spec (its trials predate it, or every trial failed)"

    def applies(self, run: RunData, options: ReportOptions) -> bool:
        return any(trial.components for trial in run.trials)

    def draw(self, run: RunData, options: ReportOptions) -> Figure:
        trials = [trial for trial in run.trials if trial.components]
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

    def caption(self, run: RunData) -> str:
        task = run.task
        if task.semantics == "classic":
            rule = "their minimum, so the lowest part (circled) is the spec's value"
        else:
            rule = (
                f"the new robustness's conjunction (nu = {task.nu:g}): while some part is below 0 the spec's value is negative and at or "
                "above the lowest part (circled); once every part is above 0 it is a mean of the parts weighted towards the lowest, "
                "so it lies between the lowest part and their mean"
            )
        text = (
            f"The spec's robustness per trial (black, on top) and each of its top-level parts below it, each on its own scale; circles mark "
            f"the lowest part. The spec's value is {rule}."
        )
        if task.placements:
            text += " With several object placements the parts are composed at each placement, and the worst placement counts."
        return text


def _wrapped(text: str, width: int = 22) -> str:
    import textwrap

    return "\n".join(textwrap.wrap(text, width)) or text


def _robustness_curves(axes, run: RunData, label_prefix: str, color: str = "tab:blue") -> None:
    numbers = np.array([trial.trial for trial in run.trials], dtype=int)
    values = robustness_of(run.trials)
    initial = np.array([trial.phase in ("sobol", "design") for trial in run.trials], dtype=bool)
    best = best_so_far(values)
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
    axes.step(numbers, best, where="post", color=color, lw=2, label=f"{label_prefix}best so far")


class GpSlices(FigureSpec):
    """GP mean and 95 % band along one or two parameters through the best point, with the
    observations (projected). Default parameters: the two with the shortest GP lengthscales."""

    name = "gp_slices"
    left_out = "fewer than three trials finished"

    def applies(self, run: RunData, options: ReportOptions) -> bool:
        return len(run.observations()[1]) >= 3 and run.best is not None

    def draw(self, run: RunData, options: ReportOptions) -> Figure:
        surrogate = Surrogate(run)
        names = list(run.space.names)
        chosen = list(options.gp_parameters or surrogate.most_relevant(2))
        figure = Figure(figsize=(5.5 * len(chosen), 4), layout="constrained")
        axes_list = np.atleast_1d(figure.subplots(1, len(chosen), squeeze=False)[0])
        for axes, name in zip(axes_list, chosen):
            cut = surrogate.slice_through(run.best.x, name)
            axes.fill_between(cut.grid, cut.mean - 1.96 * cut.std, cut.mean + 1.96 * cut.std, color="tab:blue", alpha=0.2, label="95 % band")
            axes.plot(cut.grid, cut.mean, color="tab:blue", label="GP mean")
            axes.scatter(surrogate.X[:, names.index(name)], surrogate.Y, color="k", s=12, label="trials")
            axes.axvline(run.best.x[names.index(name)], color=BEST, lw=1, label="best")
            axes.axhline(0.0, color="k", lw=0.8)
            axes.set(xlabel=name, ylabel="robustness", title=f"through the best point: {name}")
            axes.tick_params(axis="x", labelrotation=30)
        axes_list[0].legend(loc="best", fontsize=8)
        return figure

    def caption(self, run: RunData) -> str:
        return (
            "A Gaussian process refitted on the trials, along one or two parameters through the best point (the others held at the best's values): "
            "its mean, its 95 % band and the trials, projected. It shows what the trials say about these parameters "
            "(methods plan and stl model each part of the spec apart instead)."
        )


class Compare(FigureSpec):
    """Best-so-far robustness of the run and of the runs given with --compare, on one plot."""

    name = "compare"

    def applies(self, run: RunData, options: ReportOptions) -> bool:
        return bool(options.compare)

    def draw(self, run: RunData, options: ReportOptions) -> Figure:
        runs = [run, *options.compare]
        figure = Figure(figsize=(7.5, 4), layout="constrained")
        axes = figure.subplots()
        for index, each in enumerate(runs):
            label = f"{each.path.name} ({each.task.optimizer.method}, {each.task.semantics}): "
            _robustness_curves(axes, each, label_prefix=label, color=f"C{index}")
        axes.axhline(0.0, color="k", lw=1)
        axes.set(xlabel="trial", ylabel="robustness", title="best so far")
        axes.legend(loc="lower right", fontsize=8)
        return figure

    def caption(self, run: RunData) -> str:
        return f"The best robustness so far, trial by trial, of this run and of each run given with {spelled('compare')} (each in its own semantics, named in the legend)."
