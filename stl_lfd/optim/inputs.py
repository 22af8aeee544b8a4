"""`TaskInputs`: a task with the files it names read once, for everything a command does with
it: the skills' models, the objective, the fingerprint `inputs.json` keeps for `--resume`.

`load_task` reads the task file and its behaviour file; `resolve` adds the spec (parsed, its
includes followed) and the scene. A command resolves its task once and hands the result down,
so that no file of a task is read twice.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from stl_lfd.optim.task import Task
from stl_lfd.sim import Scene, load_scene
from stl_lfd.stl import ast, load_spec

if TYPE_CHECKING:
    from stl_lfd.skill.behaviour import Behaviour


@dataclass(frozen=True)
class TaskInputs:
    """A task and what its files hold.

    Attributes:
        task: the task's settings.
        spec: the parsed specification.
        scene: the scene, its objects where the scene file has them (the task's placements are
            applied per execution).
        behaviour: the behaviour (None for a task of one skill).
    """

    task: Task
    spec: ast.Spec
    scene: Scene
    behaviour: "Behaviour | None"


def resolve(task: Task, spec: ast.Spec | None = None) -> TaskInputs:
    """The inputs of `task`: its spec (or `spec`, already parsed), scene and behaviour (as
    `load_task` read it, when it did)."""
    behaviour = task.loaded_behaviour
    if behaviour is None and task.behaviour is not None:
        from stl_lfd.skill.behaviour import load_behaviour

        behaviour = load_behaviour(task.behaviour.resolve())
    return TaskInputs(task, load_spec(task.spec) if spec is None else spec, load_scene(task.scene), behaviour)
