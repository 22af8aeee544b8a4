"""What the skills became: their states and transitions before and after, and the duration
means of the states each trial follows."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import FancyArrowPatch

from stl_lfd.hsmm import HSMM
from stl_lfd.report.figures.base import BEST, FigureSpec, ReportOptions
from stl_lfd.report.run_data import RunData


class Transitions(FigureSpec):
    """The states and transitions before and after optimisation of each skill whose transitions
    are optimised: edge width by probability, the state sequence followed by the retrieval
    highlighted."""

    name = "transitions"
    left_out = "the transitions were not optimised, so the graph is the same before and after (stlopt learn --plot draws the skill's)"

    def applies(self, run: RunData, options: ReportOptions) -> bool:
        return bool(_skills_with(run, "transition_slots"))

    def draw(self, run: RunData, options: ReportOptions) -> Figure:
        skills = _skills_with(run, "transition_slots")
        figure = Figure(figsize=(12, 3.6 * len(skills)), layout="constrained")
        rows = figure.subplots(len(skills), 2, squeeze=False)
        best_models = run.best_models()
        for (before, after), skill in zip(rows, skills):
            prefix = "" if len(skills) == 1 else f"{skill}, "
            _transition_graph(before, run.models[skill], f"{prefix}unoptimised")
            _transition_graph(after, best_models[skill], f"{prefix}best (trial {run.best.trial})" if run.best else f"{prefix}best")
        return figure

    def caption(self, run: RunData) -> str:
        return (
            "The states (numbered, their duration means below them) and transitions before and after optimisation, for each skill whose "
            "transitions are optimised: edge width by the probability of leaving a state for another (each row normalised), the states "
            "the retrieval follows filled pink and the transitions it takes in red."
        )


def _skills_with(run: RunData, slots: str) -> list[str]:
    """The skills some of whose `slots` (`transition_slots`, `duration_slots`) are optimised."""
    return [skill for skill, part in run.space.parts.items() if getattr(part, slots)]


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


class Durations(FigureSpec):
    """Duration means of the states each trial's retrieval follows, stacked in the order it
    follows them (the skill's timeline per trial); one panel per skill whose durations are
    optimised."""

    name = "durations"
    left_out = "no duration mean was optimised"

    def applies(self, run: RunData, options: ReportOptions) -> bool:
        return bool(_skills_with(run, "duration_slots"))

    def draw(self, run: RunData, options: ReportOptions) -> Figure:
        skills = _skills_with(run, "duration_slots")
        figure = Figure(figsize=(9, 4 * len(skills)), layout="constrained")
        for axes, skill in zip(np.atleast_1d(figure.subplots(len(skills), 1, squeeze=False)[:, 0]), skills):
            _duration_bars(axes, run, skill)
        return figure

    def caption(self, run: RunData) -> str:
        return (
            "Duration means of the states each trial's retrieval follows, stacked in the order it follows them (states it skips are left "
            "out): the skill's timeline trial by trial, the best trial's label in red"
            + ("; the dashed line is where the rollout ends." if len(run.models) == 1 else ".")
        )


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
