"""Everything the figures of a run need, read once from its run directory."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from stl_lfd.errors import ConfigError
from stl_lfd.hsmm import HSMM
from stl_lfd.optim import RunDirectory, SearchSpace, Task, Trial, build_search_space
from stl_lfd.optim.summary import Summary
from stl_lfd.optim.tracking_fit import RunTrackingRecord, read_tracking
from stl_lfd.optim.trials import observations
from stl_lfd.signals import SignalTable
from stl_lfd.sim import Scene, load_scene
from stl_lfd.stl import ast, load_spec
from stl_lfd.stl.regions import region_boxes
from stl_lfd.stl.thresholds import Threshold, expression_thresholds, signal_thresholds


class MissingSignalsWarning(UserWarning):
    """A run directory lacks the signal files of some of its finished trials."""


@dataclass(frozen=True)
class RegionConstraint:
    """How the spec uses a region: `eventually`, `always` or `never` (always not), over an
    interval in seconds (None: the whole trace)."""

    region: str
    kind: str
    interval: tuple[float, float] | None


@dataclass
class RunData:
    """A run directory, loaded.

    Attributes:
        trials: finished trials in order; signals: trial number -> recorded signals (0 is the
        unoptimised skill); regions: name -> {signal: (lo, hi)}; constraints: the temporal
        use of each region by the spec; thresholds: signal -> the numbers the spec compares it
        with; expression_thresholds: the same for expressions of signals (`abs(box_x - shelf_x)`,
        by their text); scene: the scene at the run's one placement (as the scene file has it with several);
        missing_signals: the run's signal files that should be there and are not (a damaged
        run: their trials are left out of the figures).
    """

    path: Path
    task: Task
    summary: Summary
    models: dict[str, HSMM]
    space: SearchSpace
    trials: list[Trial]
    signals: dict[int, SignalTable]
    regions: dict[str, dict[str, tuple[float, float]]]
    constraints: list[RegionConstraint]
    tracking: RunTrackingRecord | None = None  # tracking.json, when the run learned how its robot tracks
    thresholds: dict[str, list[Threshold]] = field(default_factory=dict)
    expression_thresholds: dict[str, list[Threshold]] = field(default_factory=dict)
    scene: Scene | None = None
    missing_signals: tuple[str, ...] = ()  # signal files of finished trials that are not there (relative paths)

    @property
    def best(self) -> Trial | None:
        number = self.summary.best_trial
        return next((trial for trial in self.trials if trial.trial == number), None)

    def best_models(self) -> dict[str, HSMM]:
        best = self.best
        return self.space.apply(self.models, best.x) if best is not None else self.models

    def observations(self) -> tuple[np.ndarray, np.ndarray]:
        """`n x d` points and `n` values: what the optimiser's GP saw (failed trials at the worst
        robustness observed), so that the report's surrogate is the optimiser's."""
        X, Y = observations(self.trials)
        return X.reshape(-1, self.space.dimension), Y


def load_run(path: Path) -> RunData:
    run = RunDirectory.open(path)
    task, models = run.task(), run.models()
    if task.loaded_behaviour is not None:  # in the order the behaviour runs them
        order = [step.name for step in task.loaded_behaviour.skills]
        models = {name: models[name] for name in order if name in models}
    trials = run.trials()
    missing = tuple(str(path.relative_to(run.path)) for path in run.missing_signals())
    if missing:
        warnings.warn(f"{path}: the recorded signals {', '.join(missing)} are missing; the figures leave their trials out", MissingSignalsWarning, stacklevel=2)
    recorded = {number: run.recorded_signals(number) for number in [0] + [trial.trial for trial in trials]}
    signals = {number: table for number, table in recorded.items() if table is not None}
    spec = load_spec(task.spec)
    return RunData(
        path=Path(path),
        task=task,
        summary=run.summary(),
        models=models,
        space=build_search_space(models, task.parameters, task.source),
        trials=trials,
        signals=signals,
        regions=used_regions(spec),
        constraints=region_constraints(spec),
        tracking=read_tracking(path),
        thresholds=signal_thresholds(spec),
        expression_thresholds=expression_thresholds(spec),
        scene=placed_scene_of(task),
        missing_signals=missing,
    )


def placed_scene_of(task: Task) -> Scene | None:
    """The task's scene at its one placement, or as the scene file has it (with several
    placements, whose recorded signals are the worst placement's, or none); None when the scene
    cannot be loaded any more."""
    try:
        scene = load_scene(task.scene)
    except ConfigError:  # a scene file moved or changed since the run: the figures go without objects
        return None
    return scene.place(task.placements[0]) if len(task.placements) == 1 else scene


def used_regions(spec: ast.Spec) -> dict[str, dict[str, tuple[float, float]]]:
    """The regions (`region_boxes`) that the spec's formula uses, directly or through its
    definitions; an included file's other regions are left out."""
    definitions = {definition.name: definition.formula for definition in spec.definitions}
    used: set[str] = set()
    pending: list[ast.Node] = [spec.formula]
    while pending:
        node = pending.pop()
        if isinstance(node, ast.Ref) and node.name not in used:
            used.add(node.name)
            if node.name in definitions:
                pending.append(definitions[node.name])
        pending.extend(node.children())
    return {name: box for name, box in region_boxes(spec).items() if name in used}


def region_constraints(spec: ast.Spec) -> list[RegionConstraint]:
    """`F [a,b] R`, `G [a,b] R` and `G [a,b] !R` where R names a region, in the spec's formula."""
    regions = region_boxes(spec)
    found: list[RegionConstraint] = []

    def visit(node: ast.Node) -> None:
        if isinstance(node, (ast.Eventually, ast.Always)):
            child, negated = node.child, False
            if isinstance(child, ast.Not):
                child, negated = child.child, True
            if isinstance(child, ast.Ref) and child.name in regions:
                interval = (node.interval.lo, node.interval.hi) if node.interval is not None else None
                kind = "eventually" if isinstance(node, ast.Eventually) else ("never" if negated else "always")
                if not (kind == "eventually" and negated):
                    found.append(RegionConstraint(child.name, kind, interval))
                    return
        for child in node.children():
            visit(child)

    visit(spec.formula)
    return found


def signed_distance(table: SignalTable, box: dict[str, tuple[float, float]]) -> np.ndarray:
    """`T` signed distance to the box (negative inside): minus the box's classic robustness."""
    margins = [(hi - lo) / 2 - np.abs(table.columns[name] - (hi + lo) / 2) for name, (lo, hi) in box.items() if name in table.columns]
    return -np.min(margins, axis=0)
