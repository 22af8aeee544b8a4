"""What `--resume` checks before it continues a run: the same task file, the same command-line
options, and unchanged files outside the run directory.

A run records (in `inputs.json`) the settings its task file gave, the options the command line
overrode, and a fingerprint of each file a resume reads again (the spec with its includes, the
behaviour, the scene). Resuming with the same command plus `--resume` therefore works: options
that are given again must equal the recorded ones, options left out keep the recorded ones, and
only `--iterations` (the total number of trials) may change.
"""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

from stl_lfd.errors import RunError
from stl_lfd.optim.inputs import TaskInputs
from stl_lfd.optim.settings import recorded_optimizer
from stl_lfd.optim.task import Overrides, Task, placements_to_yaml
from stl_lfd.spelling import spelled

# Settings that may differ on resume: the budget, and the name (a label, not part of the problem).
MAY_CHANGE = ("name",)


def inputs_record(file_task: Task, overrides: Overrides, inputs: TaskInputs) -> dict[str, Any]:
    """What `inputs.json` holds for a run whose task (with its files read: `inputs`) is
    `file_task` with `overrides`."""
    return {
        "task_file": str(file_task.source.resolve()),
        "task": _comparable(file_task),
        "overrides": {key: _plain(value) for key, value in overrides.given().items() if key != "trials"},
        "fingerprint": fingerprint(inputs),
    }


def fingerprint(inputs: TaskInputs) -> dict[str, str]:
    """A digest of each input a run reads from outside its directory, by what it means (the
    parsed spec with its includes, the parsed behaviour and scene), so that editing a comment
    is not a change. The behaviour is read from its resolved path (`load_task` and `resolve`
    read it so), so that the paths inside it are the same from the task file and the run's
    record."""
    from stl_lfd.stl import format_spec

    digests = {"spec": _digest(format_spec(inputs.spec)), "scene": _digest(repr(inputs.scene))}
    if inputs.behaviour is not None:
        digests["behaviour"] = _digest(repr(inputs.behaviour))
    return digests


def check_resume(run_path: Path, recorded_inputs: TaskInputs, inputs: dict[str, Any] | None, file_task: Task, given: Overrides) -> None:
    """Refuse to resume the run at `run_path` (whose task, with its files read, is
    `recorded_inputs`) with `file_task` and the command-line options `given`, when they ask for
    something else than the run did.

    Raises:
        RunError: naming the option, setting or file that differs, with both values.
    """
    recorded = recorded_inputs.task
    for key, value in given.given().items():
        if key == "trials":
            continue
        old, new = _plain(Overrides.setting(recorded, key)), _plain(value)
        if old != new:
            raise RunError(
                f"{run_path}: {spelled(key)} cannot change on {spelled('resume')} (the run has {old}, got {new}); start a new run with another {spelled('out')}"
            )
    if inputs is None:  # a run recorded before inputs.json existed: options are all we can check
        return
    recorded_task = inputs["task"] | {"optimizer": recorded_optimizer(inputs["task"]["optimizer"], run_path)}
    difference = _first_difference(_comparable(file_task), recorded_task)
    if difference is not None:
        key, ours, theirs = difference
        raise RunError(
            f"{file_task.source}: not the task of the run in {run_path} ('{key}' is {_shown(ours)} here, {_shown(theirs)} in the run's {inputs['task_file']})"
        )
    now = fingerprint(recorded_inputs)
    for name, digest in inputs["fingerprint"].items():
        if now.get(name) != digest:
            where = {"spec": recorded.spec, "behaviour": recorded.behaviour, "scene": recorded.scene}[name]
            raise RunError(f"{where}: the {name} changed since the run started, so its trials would not compare; start a new run with another {spelled('out')}")


def _comparable(task: Task) -> dict[str, Any]:
    """The task's settings that define the problem: all but its name and the trial budget."""
    data = task.to_yaml_dict()
    for key in MAY_CHANGE:
        data.pop(key, None)
    data["optimizer"] = {key: value for key, value in data["optimizer"].items() if key != "trials"}
    return data


def _first_difference(ours: Any, theirs: Any, key: str = "") -> tuple[str, Any, Any] | None:
    """The dotted key of the first setting that differs between two task dicts, and both values."""
    if isinstance(ours, dict) and isinstance(theirs, dict):
        for name in sorted(set(ours) | set(theirs)):
            found = _first_difference(ours.get(name), theirs.get(name), f"{key}.{name}" if key else name)
            if found is not None:
                return found
        return None
    return None if ours == theirs else (key, ours, theirs)


def _plain(value: Any) -> Any:
    """Option values as recorded in JSON: paths absolute, enums by value."""
    if isinstance(value, Path):
        return str(value.resolve())
    if hasattr(value, "to_dict"):  # a Command
        return value.to_dict()
    if isinstance(value, tuple) and all(isinstance(item, dict) for item in value):  # placements
        return placements_to_yaml(value)
    return getattr(value, "value", value)


def _shown(value: Any) -> str:
    return "absent" if value is None else repr(value) if isinstance(value, str) else str(value)


def _digest(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()[:16]
