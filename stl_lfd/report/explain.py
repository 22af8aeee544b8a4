"""What a report says in words: the task, the result, the commands that go on from here, and
each figure's caption. Everything is derived from the run's own data, so that every statement
is true for the run it describes (the semantics, the method's phases, the best trial)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from stl_lfd.optim.settings import SINGLE_SKILL, Optimizer, Parameters
from stl_lfd.report.run_data import RunData

# Figures that are drawn only when the run has what they show: name -> why one is left out.
LEFT_OUT = {
    "components": "the run recorded no robustness per part of the spec (its trials predate it, or every trial failed)",
    "region_distances": "the spec names no fixed region (a box of constant x, y, z bounds) under F, G or G !",
    "durations": "no duration mean was optimised",
    "transitions": "the transitions were not optimised, so the graph is the same before and after (stlopt learn --plot draws the skill's)",
    "gp_slices": "fewer than three trials finished",
    "forces": "no trial touched anything (the contact force was zero throughout)",
    "tilt": "no trial turned the hand by more than a degree",
    "wrench": "the run recorded no wrist force-torque components, or nothing was touched",
    "objects": "the spec compares no recorded signal of the scene's objects (shaft_tilt, shaft_depth, ...) with a number",
    "tracking": "the run learned no tracking model (its backend plays the plan back, it has several object placements, or its method is not plan)",
}


def semantics_in_words(run: RunData) -> str:
    """`new robustness (nu = 1)` or `classic robustness`."""
    task = run.task
    return f"new robustness (nu = {task.nu:g})" if task.semantics == "new" else "classic robustness"


def verdict(run: RunData) -> str:
    """The result in one or two sentences: satisfied or not, best against unoptimised, first
    satisfied trial."""
    summary = run.summary
    if summary.best_robustness is None:
        return f"Every one of the {summary.trials} trials failed; the unoptimised skill scored {summary.initial_robustness:+.5f}."
    state = "Satisfied" if summary.satisfied else "Not satisfied yet"
    text = (
        f"{state}: the best trial ({summary.best_trial} of {summary.trials}) scores {summary.best_robustness:+.5f} "
        f"({semantics_in_words(run)}), where the unoptimised skill scored {summary.initial_robustness:+.5f}."
    )
    if summary.first_satisfied_trial is not None:
        text += f" The first trial that satisfied the spec was trial {summary.first_satisfied_trial}."
    elif summary.initial_robustness > 0:
        text += " The unoptimised skill already satisfied the spec; no trial did."
    return text


def task_rows(run: RunData) -> list[tuple[str, str]]:
    """The task as a table: what was run, what was optimised, how, and how long it took."""
    task, summary = run.task, run.summary
    placements = f", {len(task.placements)} object placements (the worst counts)" if task.placements else ""
    status = "complete" if summary.complete else f"stopped after {summary.trials} of {summary.budget} trials"
    return [
        ("spec", _shown_path(task.spec)),
        ("robustness", semantics_in_words(run) + "; above 0 satisfies the spec"),
        ("execution", f"{_executed_by(run)}, scene {task.scene}{placements}; {task.duration:g} s at {task.rate:g} Hz"),
        ("optimised", "; ".join(optimised_in_words(run))),
        ("parameters", f"{run.space.dimension}: {', '.join(run.space.names)}"),
        ("method", f"{_optimizer(run).phases}; seed {task.optimizer.seed}"),
        ("trials", f"{summary.trials} finished ({status}), {summary.failed_trials} failed, {summary.wall_seconds:.1f} s in all"),
        ("run directory", _shown_path(run.path)),
    ]


def _optimizer(run: RunData) -> Optimizer:
    """The run's optimiser settings with its budget as it stands (a resume may have raised it)."""
    return dataclasses.replace(run.task.optimizer, trials=run.summary.budget)


def optimised_in_words(run: RunData) -> list[str]:
    """What moves in each skill, with its bounds: `the means of states 2, 3 (x, y, z) within
    +-2 standard deviations`, ..."""
    phrases = []
    for skill, parameters in run.task.parameters.items():
        prefix = "" if skill == SINGLE_SKILL else f"{skill}: "
        phrases += [prefix + phrase for phrase in _skill_parameters(parameters)]
    return phrases


def _skill_parameters(parameters: Parameters) -> list[str]:
    means, durations = parameters.means, parameters.durations
    phrases = []
    if means.components:
        phrase = f"the means of {_states(means.components)} ({', '.join(means.coordinates)})"
        phrase += " moved together by one offset" if means.together else ""
        phrase += f" in frame {means.frame}" if means.frame else ""
        phrases.append(phrase + f", within {_deviations(means.beta)}")
    if durations.components:
        phrases.append(f"the duration means of {_states(durations.components)}, within {_deviations(durations.width)}")
    transitions = {
        "none": "transitions not optimised",
        "band": "the transition band (each state to its next one or two states)",
        "full": "every transition probability",
    }
    phrases.append(transitions[parameters.transitions])
    return phrases


def _deviations(count: float) -> str:
    return f"±{count:g} standard deviation" + ("" if count == 1 else "s")


def _states(components: tuple[int, ...] | str) -> str:
    if components == "all":
        return "all states"
    return ("state " if len(components) == 1 else "states ") + ", ".join(str(state) for state in components)


def _executed_by(run: RunData) -> str:
    """How the run's trials were executed, in words."""
    from stl_lfd.optim.summary import ASK_TELL

    executed_by = run.summary.executed_by or run.task.backend
    if ", then " in executed_by:
        return f"trials executed by {executed_by}"
    if executed_by == ASK_TELL:
        return "executed elsewhere and told (stlopt ask/tell)"
    if executed_by.startswith("command: "):
        return f"executed by the command {executed_by.removeprefix('command: ')}"
    return f"{executed_by} backend"


def _simulated(run: RunData) -> bool:
    """Whether the run's trials were simulated by stlopt (a replay shows what ran)."""
    from stl_lfd.sim.registry import backend_class, backend_names

    executed_by = run.summary.executed_by or run.task.backend
    return executed_by in backend_names() and not backend_class(executed_by).capabilities.needs_command


def commands(run: RunData) -> list[tuple[str, str]]:
    """`(command, what it does)`: watch the best trial, continue the run, redraw this report
    (paths relative to the working directory when the run lies in it, else all absolute)."""
    path = _shown_path(run.path)
    relative = not Path(path).is_absolute()
    found = []
    if run.best is not None:
        trial = run.best.trial
        where = f"in a window, or without a display as {path}/replay-trial-{trial}.mp4"
        what = f"watch the best trial again ({where})" if _simulated(run) else f"simulate the best trial ({where}); what ran on the robot is not replayed"
        found.append((f"stlopt replay {path} --trial {trial}", what))
    task_file = _task_file(run, relative)
    if task_file is not None:
        more = max(run.summary.budget, run.summary.trials) * 2
        found.append((f"stlopt optimize {task_file} --out {path} --resume -N {more}", f"continue the run up to {more} trials"))
    found.append((f"stlopt report {path}", "redraw this report (after the run went on)"))
    return found


def _task_file(run: RunData, relative: bool) -> str | None:
    from stl_lfd.optim.runs.directory import RunDirectory

    inputs = RunDirectory(run.path).inputs()
    return _shown_path(Path(inputs["task_file"]), relative) if inputs else None


def _shown_path(path: Path, relative: bool = True) -> str:
    """`path` relative to the working directory when it lies inside it (and `relative`),
    otherwise absolute."""
    resolved = Path(path).resolve()
    try:
        return str(resolved.relative_to(Path.cwd().resolve())) if relative else str(resolved)
    except ValueError:
        return str(resolved)


def caption(name: str, run: RunData) -> str:
    """The caption of figure `name` of this run."""
    best = f"the best (trial {run.best.trial}) in red" if run.best is not None else "no best trial yet"
    numbered = "darker in trial order, the unoptimised skill dashed, " + best
    semantics = semantics_in_words(run)
    optimizer = _optimizer(run)
    captions = {
        "trajectories": (
            f"End-effector paths of every trial seen from above (x-y) and from the side (x-z, y-z): {numbered}. "
            "Circles mark where the unoptimised and the best path start, squares where they end."
            + (" The coloured boxes are the regions the spec uses." if _drawn_regions(run) else "")
            + (" Black arrows: where the best trial's hand points (its approach axis), projected on each view." if _best_turns_the_hand(run) else "")
            + (
                " Grey: the objects the task is about (outlines of their bounding boxes); dotted, the path of the moved object's centre "
                "in the unoptimised and the best trial, its end as a cross."
                if _drawn_objects(run)
                else ""
            )
        ),
        "region_distances": (
            "Signed distance (m, negative inside) to each region the spec names, over the time window in which it applies: "
            "F R is met when the curve dips below 0 somewhere in its window, G R when it stays below 0 throughout, "
            f"G !R when it stays above 0; the unoptimised skill dashed, {best}."
        ),
        "robustness": (
            f"The {semantics} of each trial, the value the optimiser maximises (above 0 satisfies the spec): "
            f"the first {optimizer.initial} trials ({optimizer.initial_choice}) as squares, "
            f"then those of method {optimizer.method} as circles; the line is the best so far, the dashed line the unoptimised skill."
        ),
        "components": _components_caption(run),
        "gp_slices": (
            "A Gaussian process refitted on the trials, along one or two parameters through the best point (the others held at the best's values): "
            "its mean, its 95 % band and the trials, projected. It shows what the trials say about these parameters "
            "(methods plan and stl model each part of the spec apart instead)."
        ),
        "transitions": (
            "The states (numbered, their duration means below them) and transitions before and after optimisation, for each skill whose "
            "transitions are optimised: edge width by the probability of leaving a state for another (each row normalised), the states "
            "the retrieval follows filled pink and the transitions it takes in red."
        ),
        "durations": (
            "Duration means of the states each trial's retrieval follows, stacked in the order it follows them (states it skips are left "
            "out): the skill's timeline trial by trial, the best trial's label in red"
            + ("; the dashed line is where the rollout ends." if len(run.models) == 1 else ".")
        ),
        "forces": f"Contact force over time per trial: {numbered}." + (" Dashed green: the spec's thresholds on it." if run.thresholds.get("force") else ""),
        "wrench": (
            "The wrist force-torque sensor's components of the unoptimised skill (dashed) and the best trial (solid), in the robot's base "
            "frame with the hand's and its load's weight removed, as a Franka's external-wrench estimate gives them: force (N) above, "
            "torque about the grasp point (Nm) below."
        ),
        "objects": (
            f"The signals of the scene's objects that the spec constrains, over time per trial: {numbered}; dashed green, the spec's "
            "thresholds (the shaft's depth below the hole's rim and its offset from the hole's axis in m, its tilt from upright in rad, "
            "its speed in m/s, held 1 while both fingers touch it)."
        ),
        "tracking": (
            "How the robot followed its references. Left: the best trial's executed path against its plan (the reference) and against "
            "the prediction of the tracking model learned from the executions, per axis. Right: for every trial, the RMS "
            "error of the plan and of that final model as predictions of what was executed (the model was fitted on the trials "
            f"{_trial_list(run)}, so most of these are in-sample; tracking.json holds its held-out error). "
            + (
                "Method plan scored its candidates by this prediction."
                if run.tracking is not None and run.tracking.used
                else "The robot followed its plans within 1 mm, so method plan scored the plans themselves."
            )
        ),
        "compare": "The best robustness so far, trial by trial, of this run and of each run given with --compare (each in its own semantics, named in the legend).",
        "tilt": f"The hand's tilt (the angle between its approach axis and straight down) over time per trial: {numbered}.",
    }
    return captions.get(name, name)


def _trial_list(run: RunData) -> str:
    numbers = run.tracking.trials if run.tracking is not None else []
    return ", ".join("init" if number == 0 else str(number) for number in numbers)


def _drawn_regions(run: RunData) -> bool:
    """Whether the trajectories figure draws a region: one that bounds two of x, y, z."""
    return any(len(set(box) & {"x", "y", "z"}) >= 2 for box in run.regions.values())


def _drawn_objects(run: RunData) -> bool:
    from stl_lfd.report import objects

    return bool(objects.fixed_frame_objects(run) or objects.moving_frames(run))


def _best_turns_the_hand(run: RunData) -> bool:
    from stl_lfd.report.figures import turns_the_hand

    table = run.signals.get(run.best.trial) if run.best is not None else None
    return table is not None and turns_the_hand(table)


def _components_caption(run: RunData) -> str:
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


def left_out(run: RunData, drawn: set[str]) -> list[tuple[str, str]]:
    """`(figure, why)` for each figure this run does not show."""
    return [(f"{name}.png", why) for name, why in LEFT_OUT.items() if name not in drawn]
