"""`TaskInputs`: a task with the files it names read once, for everything a command does with
it: the skills' models, the objective, the fingerprint `inputs.json` keeps for `--resume`.

`load_task` reads the task file and its behaviour file; `resolve` adds the spec (parsed, its
includes followed) and the scene. A command resolves its task once and hands the result down,
so that no file of a task is read twice; `task_models` learns or loads the task's skills.
"""

from __future__ import annotations

from dataclasses import dataclass

from stl_lfd.errors import ConfigError, SpecError
from stl_lfd.hsmm import HSMM, learn_from_folder, load_model
from stl_lfd.optim.settings import SINGLE_SKILL
from stl_lfd.optim.task import Task, read_behaviour
from stl_lfd.sim import Scene, load_scene
from stl_lfd.skill.behaviour import Behaviour, behaviour_models
from stl_lfd.stl import SpecParts, ast, load_spec, split_spec


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
    behaviour: Behaviour | None


def resolve(task: Task, spec: ast.Spec | None = None) -> TaskInputs:
    """The inputs of `task`: its spec (or `spec`, already parsed), scene and behaviour (as
    `load_task` read it, when it did)."""
    behaviour = task.loaded_behaviour
    if behaviour is None and task.behaviour is not None:  # a task built in Python, not read by load_task
        behaviour = read_behaviour(task.behaviour)
    return TaskInputs(task, load_spec(task.spec) if spec is None else spec, load_scene(task.scene), behaviour)


def task_models(inputs: TaskInputs) -> dict[str, HSMM]:
    """The skills of a task: learned from its demos, loaded, or those of its behaviour."""
    task = inputs.task
    if inputs.behaviour is not None:
        return behaviour_models(inputs.behaviour)
    if task.demos is not None:
        return {SINGLE_SKILL: learn_from_folder(task.demos, task.states)[0]}
    return {SINGLE_SKILL: load_model(task.model)}


def spec_parts(inputs: TaskInputs) -> SpecParts:
    """The spec split into its top-level parts for the task's semantics, after the checks that
    find its problems before any trial: windows that reach past the rollout duration, and
    signals the scene's rollouts do not record."""
    task, scene = inputs.task, inputs.scene
    parts = split_spec(inputs.spec, task.semantics, task.nu, source=str(task.spec))
    horizon = max(function.horizon for function in parts.functions)  # a conjunction looks as far as its parts
    if horizon > task.duration + 1e-9:
        raise ConfigError(
            f"{task.source}: the spec {task.spec.name} looks {horizon:g} s ahead but rollouts last "
            f"{task.duration:g} s ('duration'); lengthen the rollouts or shorten the spec's windows"
        )
    unknown = sorted(parts.signals - set(scene.recorded_signals))
    if unknown:
        raise SpecError(
            f"signal {', '.join(unknown)} is not recorded by rollouts in the scene {scene.name} (they record {', '.join(scene.recorded_signals)})",
            str(task.spec),
        )
    return parts
