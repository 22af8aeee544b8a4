"""What a report says in words: the task, the result and the commands that go on from here
(each figure's caption is its `FigureSpec`'s). Everything is derived from the run's own data,
so that every statement is true for the run it describes (the semantics, the method's phases,
the best trial)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from stl_lfd.optim.settings import SINGLE_SKILL, Optimizer, Parameters
from stl_lfd.report.run_data import RunData


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
