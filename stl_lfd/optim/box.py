"""A task's search box before any trial (`stlopt optimize --dry-run`): each parameter's bounds in
its own units, and what the plans at the box's centre and corners say of each part of the spec.

A plan is the reference itself, executed by the kinematic backend: it knows where the hand
goes and what it carries, not what it touches, so a part on the force reads as if nothing were
touched. A part that no plan of the box satisfies, while the unoptimised skill misses it too,
says that the box is likely too small (a larger `beta`, or other states to move) before any
trial is spent.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from stl_lfd.hsmm import HSMM
from stl_lfd.optim.inputs import TaskInputs, resolve, task_models
from stl_lfd.optim.methods.base import to_unit
from stl_lfd.optim.methods.plan_model import Plan
from stl_lfd.optim.objective import objective_for
from stl_lfd.optim.task import Overrides, Task

MAX_CORNERS = 64  # corners planned: all of them up to 6 parameters, a fixed sample beyond


@dataclass(frozen=True)
class ParameterBox:
    """One parameter's range, in `unit` (`mm`, `deg`, `s` or blank for a probability)."""

    name: str
    unit: str
    initial: float
    lower: float
    upper: float


@dataclass(frozen=True)
class PartPlans:
    """What the plans say of one part of the spec: its robustness at the unoptimised point and
    at the box's centre, the best over the planned points, and how many of them satisfy it."""

    name: str
    unoptimised: float
    centre: float
    best: float
    satisfied: int


@dataclass(frozen=True)
class BoxReport:
    """The box of a task: its parameters, and the plans of `points` points (the unoptimised one,
    the centre and corners) per part of the spec, then of the whole spec (with several parts)."""

    parameters: tuple[ParameterBox, ...]
    parts: tuple[PartPlans, ...]
    points: int


def task_box(file_task: Task, given: Overrides = Overrides()) -> BoxReport:
    """The box of a task file's task with the settings `given` on top, as a new run of it
    would search it (its skills learned or loaded first)."""
    task = given.fitted_to(file_task)[0].applied_to(file_task)
    inputs = resolve(task)
    return box_report(inputs, task_models(inputs))


def box_report(inputs: TaskInputs, models: dict[str, HSMM], max_corners: int = MAX_CORNERS) -> BoxReport:
    """The box of the task `inputs` on its skills `models` (see the module docstring)."""
    space, objective = objective_for(inputs, models, execute=False)
    points = np.vstack([space.initial, (space.lower + space.upper) / 2, corners(space.lower, space.upper, max_corners)])
    plan = Plan(objective.plan_score(), space.bounds)  # a point without a plan gives NaN
    values = plan(to_unit(points, space.bounds))[:, : len(objective.composition.names)]
    groups = values.reshape(len(points), objective.composition.groups, -1)  # a group of the parts per placement
    whole = objective.parts.compose(np.nan_to_num(groups, nan=-np.inf)).min(axis=1)
    columns = [*zip(objective.composition.names, values.T), *([("the whole spec", whole)] if values.shape[1] > 1 else [])]
    parts = tuple(PartPlans(name, float(column[0]), float(column[1]), float(np.nanmax(column)), int(np.sum(column > 0))) for name, column in columns)
    parameters = tuple(ParameterBox(name, *_shown(name, space.initial[i], space.lower[i], space.upper[i])) for i, name in enumerate(space.names))
    return BoxReport(parameters, parts, len(points))


def corners(lower: np.ndarray, upper: np.ndarray, count: int) -> np.ndarray:
    """`k x d` corners of the box: all `2^d` when there are at most `count`, else `count` of
    them drawn with a fixed seed (the same for the same box)."""
    dimension = len(lower)
    if 2**dimension <= count:
        choices = (np.arange(2**dimension)[:, None] >> np.arange(dimension)) & 1
    else:
        rng, choices = np.random.default_rng(0), np.empty((0, dimension), dtype=int)
        while len(choices) < count:  # distinct corners, in the order drawn
            drawn = np.vstack([choices, rng.integers(0, 2, size=(count, dimension))])
            choices = drawn[np.sort(np.unique(drawn, axis=0, return_index=True)[1])][:count]
    return np.where(choices == 1, upper, lower)


def _shown(name: str, initial: float, lower: float, upper: float) -> tuple[str, float, float, float]:
    """A parameter's unit and values as shown: positions in mm, angles in degrees, durations in
    seconds, transition probabilities as they are."""
    coordinate = name.rsplit(".", 1)[-1]
    if coordinate in ("x", "y", "z"):
        return "mm", 1000 * initial, 1000 * lower, 1000 * upper
    if coordinate in ("rx", "ry", "rz"):
        return "deg", *np.degrees([initial, lower, upper]).tolist()
    if "duration" in name:
        return "s", initial, lower, upper
    return "", initial, lower, upper
