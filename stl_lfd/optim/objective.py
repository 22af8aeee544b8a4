"""The objective of a run: a point -> adapted models -> reference -> rollout -> robustness of the
recorded signals and of the spec's parts; and its plan (the same on the kinematic backend).

Its pieces: `scoring` (signals -> the parts' robustness), `plans` (the references of many
points, kept for a while), `placements` (a trial at several placements of the objects), and
`inputs` (the task's files, read once, and its skills' models)."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from stl_lfd.errors import ExecutionError
from stl_lfd.hsmm import HSMM
from stl_lfd.optim.inputs import TaskInputs, spec_parts
from stl_lfd.optim.placements import placement_composition, spec_composition, worst_outcome
from stl_lfd.optim.plans import PlanCache
from stl_lfd.optim.scoring import Scorer
from stl_lfd.optim.space import SearchSpace, build_search_space
from stl_lfd.optim.task import Task
from stl_lfd.optim.trials import Outcome
from stl_lfd.signals import SignalTable
from stl_lfd.sim import Backend, BackendOptions, Reference, Scene, new_backend
from stl_lfd.sim.grasp_model import GraspModel
from stl_lfd.sim.tracking_model import TrackingModel
from stl_lfd.skill.behaviour import Behaviour
from stl_lfd.skill.placed import PlacedSkill, placed_scene
from stl_lfd.stl import SpecParts


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
        self.plans = PlanCache(models, space, self.placed)
        self.scorer = Scorer(parts)
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
        """File the executions in `folder` (the run directory), where the backend files them."""
        if self.backend is not None:
            self.backend.file_executions(folder=Path(folder))

    def __call__(self, x: np.ndarray, trial: int = 0) -> Outcome:
        return self.evaluate(self.space.apply(self.models, x), trial)

    def planned(self, tracking: TrackingModel | None = None, grasp: GraspModel | None = None) -> "SkillObjective":
        """This objective on the kinematic backend: it scores the plan (the reference itself),
        or with `tracking` the plan's execution as the tracking model predicts it (carried
        objects where `grasp` says they sit in the hand)."""
        from stl_lfd.sim.kinematic import KinematicBackend
        from stl_lfd.sim.tracking_model import PredictingBackend

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
            outcomes = planned.execute_all(self.plans.references(points, keep=tracking is not None))
            return np.array([list(outcome.components.values()) + [outcome.routes[route] for route in routes] for outcome in outcomes], dtype=float)

        return score

    def reference(self, models: dict[str, HSMM]) -> Reference:
        """What executing `models` means at the first placement (see `PlacedSkill.reference`)."""
        return self.placed[0].with_models(models).reference()

    def evaluate(self, models: dict[str, HSMM], trial: int = 0) -> Outcome:
        """Execute `models` as trial `trial` (0: the unoptimised skill) and score the signals."""
        if self.backend is not None:
            self.backend.file_executions(trial=trial)
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
        return [worst_outcome([outcomes[index] for outcomes in placements], self.composition) for index in range(len(references[0]))]

    def score(self, signals: SignalTable) -> Outcome:
        """The robustness of recorded `signals`, and of each of the spec's parts."""
        return self.scorer.score(signals)

    def score_all(self, recordings: Sequence[SignalTable]) -> list[Outcome]:
        return self.scorer.score_all(recordings)


def objective_for(inputs: TaskInputs, models: dict[str, HSMM], execute: bool = True) -> tuple[SearchSpace, SkillObjective]:
    """The parameter space and the objective of a task (with a backend of its own unless not
    `execute`); the spec's problems are found first (`inputs.spec_parts`)."""
    task = inputs.task
    space = build_search_space(models, task.parameters, task.source)
    parts = spec_parts(inputs)
    backend = new_backend(task.backend, BackendOptions(command=task.command)) if execute else None
    return space, SkillObjective(models, space, task, inputs.behaviour, inputs.scene, parts, backend)
