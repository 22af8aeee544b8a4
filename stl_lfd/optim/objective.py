"""The objective of a run: a point -> adapted models -> reference -> rollout -> robustness of the
recorded signals and of the spec's parts; and its plan (the same on the kinematic backend)."""

from __future__ import annotations

import copy
from collections import OrderedDict
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from stl_lfd.errors import ConfigError, ExecutionError, SignalError, SpecError
from stl_lfd.hsmm import HSMM, learn_from_folder, load_model
from stl_lfd.optim.inputs import TaskInputs
from stl_lfd.optim.methods.base import Composition
from stl_lfd.optim.settings import SINGLE_SKILL
from stl_lfd.optim.space import SearchSpace, build_search_space
from stl_lfd.optim.task import Task
from stl_lfd.optim.trials import Outcome
from stl_lfd.poses import Pose
from stl_lfd.signals import SignalTable
from stl_lfd.sim import Backend, BackendOptions, CommandBackend, Reference, Scene, new_backend
from stl_lfd.sim.grasp import GraspModel
from stl_lfd.sim.tracking import TrackingModel
from stl_lfd.skill.behaviour import Behaviour, behaviour_models
from stl_lfd.skill.placed import PlacedSkill, placed_scene
from stl_lfd.stl import SpecParts, split_spec

# How much of the references it retrieved `plan_references` keeps: method plan's pool of 128
# candidates and its refinement draws, for a task of phi1's size (about 0.3 MB a reference).
PLANNED_REFERENCE_BYTES = 128 * 2**20


class SkillObjective:
    """x -> adapted models -> (behaviour) reference -> rollout -> robustness of the recorded
    signals and of the spec's top-level parts (payload: the signals). It owns its backend (one
    simulated world for all its rollouts) until `close`; without a backend (`execute=False` in
    `objective_for`) it only scores signals recorded elsewhere.

    With several object placements (`task.placements`), a trial executes once per placement and
    its robustness is the worst; its parts are then the spec's parts at each placement, and its
    payload the signals of the worst placement."""

    def __init__(
        self, models: dict[str, HSMM], space: SearchSpace, task: Task, behaviour: Behaviour | None, scene: Scene, parts: SpecParts, backend: Backend | None
    ) -> None:
        self.models, self.space, self.task, self.parts = models, space, task, parts
        scenes = [placed_scene(scene, placement, str(task.source)) for placement in task.placements] or [scene]
        self.placed = [PlacedSkill(models, behaviour, scene, task.duration) for scene in scenes]  # one per placement
        self.scene = scenes[0]
        self.backend = backend
        self._references: OrderedDict[bytes, list[Reference]] = OrderedDict()  # see plan_references
        self._reference_sizes: dict[bytes, int] = {}  # bytes of each kept point's references
        # The parts the search method models: the spec's, or the spec's at each placement.
        self.composition = spec_composition(parts) if len(scenes) == 1 else placement_composition(parts, task.placements)

    def close(self) -> None:
        if self.backend is not None:
            self.backend.close()

    @property
    def plays_the_plan(self) -> bool:
        """Whether executions are the plan itself (the kinematic backend): no tracking to learn."""
        return self.backend is not None and self.backend.capabilities.plays_the_plan

    def exchange_in(self, folder: Path) -> None:
        """Write the command backend's exchange folders in `folder` (the run directory)."""
        if isinstance(self.backend, CommandBackend):
            self.backend.folder = Path(folder)

    def __call__(self, x: np.ndarray, trial: int = 0) -> Outcome:
        return self.evaluate(self.space.apply(self.models, x), trial)

    def planned(self, tracking: TrackingModel | None = None, grasp: GraspModel | None = None) -> "SkillObjective":
        """This objective on the kinematic backend: it scores the plan (the reference itself),
        or with `tracking` the plan's execution as the tracking model predicts it (carried
        objects where `grasp` says they sit in the hand)."""
        from stl_lfd.sim.kinematic import KinematicBackend
        from stl_lfd.sim.tracking import PredictingBackend

        plan = copy.copy(self)
        plan.backend = KinematicBackend() if tracking is None else PredictingBackend(tracking, grasp)
        return plan

    def plan_score(self, tracking: TrackingModel | None = None, grasp: GraspModel | None = None) -> Callable[[np.ndarray], np.ndarray]:
        """`b x d` points -> `b x o`: the plan's robustness of each part, then route, at each
        point (the prior of method `plan`), the points' plans retrieved together (and, with
        `tracking`, executed as it predicts, with `grasp`'s objects in the hand); raises when a
        point has no plan."""
        planned, routes = self.planned(tracking, grasp), self.composition.route_names

        def score(points: np.ndarray) -> np.ndarray:
            outcomes = planned.execute_all(self.plan_references(points, keep=tracking is not None))
            return np.array([list(outcome.components.values()) + [outcome.routes[route] for route in routes] for outcome in outcomes], dtype=float)

        return score

    def plan_references(self, points: np.ndarray, keep: bool = False) -> list[list[Reference]]:
        """The references of `b x d` points at each placement (placement x point), retrieved
        together. With `keep`, those retrieved lately are kept (up to PLANNED_REFERENCE_BYTES,
        the oldest dropped first): the plan scores of successive tracking models share them (a
        point's reference does not depend on the model)."""
        keys = [np.asarray(point, dtype=float).tobytes() for point in points]
        known = self._references if keep else {}
        new = list(dict.fromkeys(key for key in keys if key not in known))
        retrieved: dict[bytes, list[Reference]] = {}
        if new:
            placements = [placed.references([self.space.apply(self.models, np.frombuffer(key)) for key in new]) for placed in self.placed]
            retrieved = {key: [references[index] for references in placements] for index, key in enumerate(new)}
        result = [[(retrieved.get(key) or known[key])[placement] for key in keys] for placement in range(len(self.placed))]
        if keep:
            self._keep(keys, retrieved)
        return result

    def _keep(self, keys: list[bytes], retrieved: dict[bytes, list[Reference]]) -> None:
        """Keep the `retrieved` references and mark `keys` as the latest used."""
        self._references.update(retrieved)
        self._reference_sizes.update({key: sum(reference_bytes(reference) for reference in references) for key, references in retrieved.items()})
        for key in keys:
            self._references.move_to_end(key)
        total = sum(self._reference_sizes.values())
        while total > PLANNED_REFERENCE_BYTES and self._references:
            key, _ = self._references.popitem(last=False)
            total -= self._reference_sizes.pop(key)

    def reference(self, models: dict[str, HSMM]) -> Reference:
        """What executing `models` means at the first placement (see `PlacedSkill.reference`)."""
        return self.placed[0].with_models(models).reference()

    def evaluate(self, models: dict[str, HSMM], trial: int = 0) -> Outcome:
        """Execute `models` as trial `trial` (0: the unoptimised skill) and score the signals."""
        if isinstance(self.backend, CommandBackend):
            self.backend.trial = trial
        return self.evaluate_all([models])[0]

    def evaluate_all(self, models: Sequence[dict[str, HSMM]]) -> list[Outcome]:
        """`evaluate` N sets of models: their references retrieved together, then executed one
        after the other and scored together."""
        return self.execute_all([placed.references(models) for placed in self.placed])

    def execute_all(self, references: list[list[Reference]]) -> list[Outcome]:
        """Execute and score N references at each placement (placement x N): one outcome each."""
        if self.backend is None:
            raise ExecutionError("this objective only scores signals recorded elsewhere (it has no backend)")
        placements = [
            self.score_all([placed.execute(self.backend, self.task.rate, reference=reference).signals for reference in placement_references])
            for placed, placement_references in zip(self.placed, references)
        ]
        return [self._worst([outcomes[index] for outcomes in placements]) for index in range(len(references[0]))]

    def _worst(self, outcomes: list[Outcome]) -> Outcome:
        """One trial's outcome from its `outcomes` at each placement: the worst robustness and
        its signals, and the parts at every placement."""
        if len(outcomes) == 1:
            return outcomes[0]
        worst = min(outcomes, key=lambda outcome: outcome.robustness)
        values = [value for outcome in outcomes for value in outcome.components.values()]
        return Outcome(worst.robustness, worst.payload, dict(zip(self.composition.names, values)))

    def score(self, signals: SignalTable) -> Outcome:
        """The robustness of recorded `signals`, and of each of the spec's parts."""
        return self.score_all([signals])[0]

    def score_all(self, recordings: Sequence[SignalTable]) -> list[Outcome]:
        """`score` each of the `recordings`; those on the same sample times as a `B x T` batch."""
        for signals in recordings:
            missing = sorted(self.parts.signals - set(signals.columns))
            if missing:
                raise SignalError(f"{signals.source}: no column {', '.join(missing)}, which the spec needs")
        outcomes: list[Outcome | None] = [None] * len(recordings)
        groups: dict[bytes, list[int]] = {}
        for index, signals in enumerate(recordings):
            groups.setdefault(np.asarray(signals.times).tobytes(), []).append(index)
        for indices in groups.values():
            batch = {name: np.stack([recordings[index].columns[name] for index in indices]) for name in self.parts.signals}
            times = recordings[indices[0]].times
            # The spec is evaluated once, part by part; composing the parts is exactly its robustness.
            values = np.atleast_2d(self.parts(batch, times))
            routes = self.parts.route_values(batch, times)
            for row, index in enumerate(indices):
                outcomes[index] = Outcome(
                    self.parts.compose(values[row]),
                    recordings[index],
                    dict(zip(self.parts.names, values[row].tolist())),
                    {name: float(value[row]) for name, value in routes.items()} or None,
                )
        return outcomes


def reference_bytes(reference: Reference) -> int:
    """The memory a reference's arrays take."""
    return sum(value.nbytes for value in vars(reference).values() if isinstance(value, np.ndarray))


def task_models(inputs: TaskInputs) -> dict[str, HSMM]:
    """The skills of a task: learned from its demos, loaded, or those of its behaviour."""
    task = inputs.task
    if inputs.behaviour is not None:
        return behaviour_models(inputs.behaviour)
    if task.demos is not None:
        return {SINGLE_SKILL: learn_from_folder(task.demos, task.states)[0]}
    return {SINGLE_SKILL: load_model(task.model)}


def objective_for(inputs: TaskInputs, models: dict[str, HSMM], execute: bool = True) -> tuple[SearchSpace, SkillObjective]:
    """The parameter space and the objective of a task (with a backend of its own unless not
    `execute`); spec problems are found here, before any trial: unknown signals, and windows
    that reach past the rollout duration."""
    task = inputs.task
    space = build_search_space(models, task.parameters, task.source)
    parts = split_spec(inputs.spec, task.semantics, task.nu, source=str(task.spec))
    horizon = max(function.horizon for function in parts.functions)  # a conjunction looks as far as its parts
    if horizon > task.duration + 1e-9:
        raise ConfigError(
            f"{task.source}: the spec {task.spec.name} looks {horizon:g} s ahead but rollouts last "
            f"{task.duration:g} s ('duration'); lengthen the rollouts or shorten the spec's windows"
        )
    scene = inputs.scene
    unknown = sorted(parts.signals - set(scene.recorded_signals))
    if unknown:
        raise SpecError(
            f"signal {', '.join(unknown)} is not recorded by rollouts in the scene {scene.name} (they record {', '.join(scene.recorded_signals)})",
            str(task.spec),
        )
    backend = new_backend(task.backend, BackendOptions(command=task.command)) if execute else None
    return space, SkillObjective(models, space, task, inputs.behaviour, scene, parts, backend)


def spec_composition(parts: SpecParts) -> Composition:
    """The spec's parts and routes, as the search methods model them."""
    return Composition(tuple(parts.names), parts.semantics, 1, tuple((route.name, route.part) for route in parts.routes))


def placement_composition(parts: SpecParts, placements: tuple[dict[str, Pose], ...]) -> Composition:
    """The spec's parts at each placement, named `placement 2 (holder 0.6,0.25,0.04 yaw 0.3): PART`,
    composed within a placement by the spec's semantics and by the minimum over placements
    (each part at each placement gets its own GP output; no routes)."""
    labels = []
    for index, placement in enumerate(placements):
        poses = ", ".join(f"{name} {','.join(f'{v:g}' for v in pose.position)} yaw {pose.yaw:g}" for name, pose in placement.items())
        labels.append(f"placement {index + 1} ({poses})")
    return Composition(tuple(f"{label}: {part}" for label in labels for part in parts.names), parts.semantics, len(labels))


@dataclass(frozen=True)
class ObjectiveFactory:
    """Makes the objective of a task in another process (a parallel worker): picklable, so
    that the worker builds its own world, or its own executor command, once at start-up, from
    the task's `inputs` as read here. `run_dir`: where the command backend's exchange folders go
    (None: a scratch folder)."""

    inputs: TaskInputs
    models: dict[str, HSMM]
    run_dir: Path | None = None

    def __call__(self) -> SkillObjective:
        _, objective = objective_for(self.inputs, self.models)
        if self.run_dir is not None:
            objective.exchange_in(self.run_dir)
        return objective
