"""The task to run when `stlopt optimize --spec SPEC` is given no task file: the task file that
names the spec (in `configs/` beside the spec's folder), or a default task built from the spec
and the demonstrations (`--demos DIR`) or a model file (`--model FILE`).

The default task (`DEFAULTS`) executes in free space on the PyBullet Panda, scores the new
robustness, and optimises the means of every state but the first (the start) in x, y and z
within 2 standard deviations, every duration mean within 1 standard deviation, and the reduced
transition band, with method `plan`: 8 initial trials, 32 in all. Each rollout lasts as long as
the longest demonstration (or the model's expected duration), or the spec's horizon if that is
longer, rounded up to a whole second.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any, Callable

from stl_lfd.choices import DEFAULT_SEMANTICS
from stl_lfd.errors import ConfigError
from stl_lfd.optim.task import Task, load_task, parse_task
from stl_lfd.sim.registry import DEFAULT_BACKEND
from stl_lfd.spelling import spelled
from stl_lfd.yamlfile import read_yaml

DEFAULTS: dict[str, Any] = {
    "scene": "free_space",
    "backend": DEFAULT_BACKEND,
    "semantics": DEFAULT_SEMANTICS,
    "rate": 100,
    "optimizer": {"method": "plan", "initial": 8, "trials": 32, "seed": 0},
}
STATES = 6  # states learned from --demos


def task_file_naming(spec: Path) -> Path | None:
    """The task file in `configs/` beside the spec's folder whose `spec:` is `spec`: the one
    named after the spec if several are, else the only one; None when none is. A ConfigError
    lists them when several are and none is named after the spec."""
    folder = Path(spec).resolve().parent.parent / "configs"
    naming = [path for path in sorted(folder.glob("*.yaml")) if _names_spec(path, Path(spec).resolve())]
    if len(naming) > 1:
        named_after = [path for path in naming if path.stem == Path(spec).stem]
        if not named_after:
            listed = ", ".join(str(path) for path in naming)
            raise ConfigError(f"{spec}: several task files name this spec ({listed}); give one of them")
        naming = named_after
    return naming[0] if naming else None


def _names_spec(path: Path, spec: Path) -> bool:
    try:
        data = read_yaml(path)
    except ConfigError:  # a broken task file elsewhere in configs/ is not this command's business
        return False
    return isinstance(data, dict) and isinstance(data.get("spec"), str) and (path.parent / data["spec"]).resolve() == spec


def default_task(spec: Path, demos: Path | None = None, model: Path | None = None) -> Task:
    """The default task (see the module's docstring) for `spec` and the skill in `demos` or
    `model` (exactly one)."""
    if demos is not None and model is not None:
        raise ConfigError(f"{spec}: give {spelled('demos')} DIR or {spelled('model')} FILE for the default task, not both")
    if demos is None and model is None:
        raise ConfigError(
            f"{spec}: no task file in configs/ names this spec; give a task file, or {spelled('demos')} DIR or {spelled('model')} FILE to build a default task"
        )
    states, seconds = _skill_size(demos, model)
    spec = Path(spec).resolve()
    data = DEFAULTS | {
        "name": spec.stem,
        "spec": str(spec),
        "duration": math.ceil(max(seconds, _horizon(spec))),
        "parameters": {
            "means": {"components": list(range(2, states + 1)), "coordinates": ["x", "y", "z"], "beta": 2.0},
            "durations": {"components": "all", "width": 1.0},
            "transitions": "band",
        },
    }
    data |= {"demos": str(Path(demos).resolve()), "states": states} if demos is not None else {"model": str(Path(model).resolve())}
    return parse_task(data, Path.cwd() / f"{spec.stem} (default task)")


def _skill_size(demos: Path | None, model: Path | None) -> tuple[int, float]:
    """The number of states and the duration (s) of the skill: the longest demonstration, or
    the model's expected duration."""
    needs_file = "a skill that follows objects needs a task file (its scene and where the objects stand)"
    if demos is not None:
        from stl_lfd.hsmm import load_demo_frames, load_demos

        recordings = load_demos(demos)
        if load_demo_frames(recordings) is not None:
            raise ConfigError(f"{demos}: the demonstrations have frame sidecars; {needs_file}")
        return STATES, max(float(demo.times[-1] - demo.times[0]) for demo in recordings)
    from stl_lfd.hsmm import TPHSMM, load_model, retrieve

    loaded = load_model(model)
    if isinstance(loaded, TPHSMM):
        raise ConfigError(f"{model}: the model is learned in object frames; {needs_file}")
    return loaded.n_states, float(retrieve(loaded).times[-1])


def _horizon(spec: Path) -> float:
    from stl_lfd.stl import horizon, load_spec
    from stl_lfd.stl.parser import resolve

    parsed = load_spec(spec)
    return horizon(resolve(parsed))


def task_to_run(task_file: Path | None, spec: Path | None, demos: Path | None, model: Path | None, say: Callable[[str], None] = lambda message: None) -> Task:
    """What `stlopt optimize` runs: the task file's task; without one, the task file that names
    `spec` (said through `say`), or a default task for `spec` on `demos` or `model`."""
    if task_file is not None:
        if demos is not None or model is not None:
            raise ConfigError(f"{spelled('demos')} and {spelled('model')} build a task without a task file; the task file names its skill")
        return load_task(task_file)
    if spec is None:
        raise ConfigError(f"give a task file (e.g. configs/phi1.yaml), or {spelled('spec')} SPEC")
    if not Path(spec).is_file():
        raise ConfigError(f"{spec}: no such spec file")
    found = task_file_naming(spec) if demos is None and model is None else None
    if found is not None:
        shown = os.path.relpath(found) if found.is_relative_to(Path.cwd()) else found
        say(f"using the task file {shown}, which names {spec}")
        return load_task(found)
    return default_task(spec, demos, model)
