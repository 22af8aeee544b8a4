"""A run's tracking model: how its robot followed the references of the trials executed so far
(`stl_lfd.sim.tracking_model`), so that method `plan` scores a candidate by its predicted execution.

The executions are the unoptimised skill's and the finished trials': each trial's reference is
rebuilt from its point (the plan is a pure function of the point) and its positions are read
from the run directory, so that a resumed run fits the same models and proposes the same points.
The latest model is kept in `tracking.json` for the report and the API, with how well it and
the plan predicted each execution it was fitted on, and the best of them as paths over time.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from stl_lfd.errors import RunError
from stl_lfd.files import write_atomically
from stl_lfd.hsmm import HSMM
from stl_lfd.optim.objective import SkillObjective
from stl_lfd.optim.space import SearchSpace
from stl_lfd.optim.trials import Trial
from stl_lfd.signals import SignalTable
from stl_lfd.sim.grasp_model import GraspModel, InHand, carried_poses
from stl_lfd.sim.tracking_model import Execution, TrackingModel

TRACKING_FILE = "tracking.json"
# Below this departure from the plan (m, RMS per axis over the executions so far) the plan is
# taken as the execution: predictions would change nothing a spec can tell, at the cost of
# planning every candidate again after each trial.
FOLLOWS_THE_PLAN = 0.001
PATH_SAMPLES = 500  # the best execution's paths in tracking.json, at most this many samples (a figure's resolution)


class RunTracking:
    """The tracking models of a run, one per set of executed trials.

    Args:
        objective, models, space: the run's, to rebuild a trial's reference from its point.
        recorded_signals: trial number (0: the unoptimised skill) -> its recorded signals, or
            None (`RunStore.recorded_signals`).
        folder: where `tracking.json` is written (None: nowhere).
    """

    def __init__(
        self, objective: SkillObjective, models: dict[str, HSMM], space: SearchSpace, recorded_signals: Callable[[int], SignalTable | None], folder: Path | None
    ) -> None:
        self.objective, self.models, self.space = objective, models, space
        self.recorded_signals, self.folder = recorded_signals, folder
        self._executions: dict[int, Execution | None] = {}
        self._carried: dict[int, dict[str, tuple[InHand, InHand]]] = {}  # trial -> where its objects sat in the hand
        self._latest: tuple[tuple[int, ...], TrackingModel, GraspModel] | None = None

    def model(self, history: Sequence[Trial]) -> tuple[tuple[int, ...], TrackingModel, GraspModel]:
        """The tracking and grasp models fitted on the unoptimised skill's execution and those of
        `history`'s successful trials, and the trial numbers they were fitted on (their identity)."""
        numbers = tuple(
            number for number in [0, *(trial.trial for trial in history if trial.robustness is not None)] if self._execution(number, history) is not None
        )
        if self._latest is None or self._latest[0] != numbers:
            executions = [self._executions[number] for number in numbers]
            model = TrackingModel().fit(executions, plan_within=FOLLOWS_THE_PLAN) if numbers else TrackingModel()
            grasp = GraspModel().fit_poses([self._carried[number] for number in numbers])
            self._latest = (numbers, model, grasp)
            self._write(numbers, model, grasp, history)
        return self._latest

    def plan_score(self, history: Sequence[Trial]) -> tuple[tuple[int, ...] | None, Callable[[np.ndarray], np.ndarray] | None]:
        """The plan score (`SkillObjective.plan_score`) through the models of `history`, and the
        models' identity (the same identity, the same score); `(None, None)` while the robot
        follows the plan within FOLLOWS_THE_PLAN and holds objects as it grasped them (the plan
        itself is the prediction)."""
        numbers, model, grasp = self.model(history)
        if not used(model, grasp):
            return None, None
        return numbers, self.objective.plan_score(model, grasp)

    def _execution(self, number: int, history: Sequence[Trial]) -> Execution | None:
        if number not in self._executions:
            x = self.space.initial if number == 0 else next(trial.x for trial in history if trial.trial == number)
            signals = self.recorded_signals(number)
            self._executions[number] = execution_of(self.objective, self.space.apply(self.models, x), signals) if signals is not None else None
            self._carried[number] = carried_poses(signals, self.objective.scene) if signals is not None else {}
        return self._executions[number]

    def _write(self, numbers: tuple[int, ...], model: TrackingModel, grasp: GraspModel, history: Sequence[Trial]) -> None:
        if self.folder is None:
            return
        paths = {number: predicted_paths(self._executions[number], model) for number in numbers}
        errors = {str(number): {"plan": _rms(path.planned - path.executed), "model": _rms(path.predicted - path.executed)} for number, path in paths.items()}
        record = {"trials": list(numbers), "used": used(model, grasp), **model.to_dict(), "grasp": grasp.to_dict(), "errors": errors}
        robustness = {trial.trial: trial.robustness for trial in history if trial.trial in paths}
        if robustness:
            best = max(robustness, key=robustness.get)
            record["best"] = {"trial": best, **paths[best].thinned(PATH_SAMPLES).to_dict()}
        write_atomically(self.folder / TRACKING_FILE, json.dumps(record, indent=2) + "\n")


@dataclass(frozen=True)
class PredictedPaths:
    """One execution against its predictions: `T` sample times and `T x 3` positions, executed,
    planned (the reference at those times) and predicted by a tracking model."""

    times: np.ndarray
    executed: np.ndarray
    planned: np.ndarray
    predicted: np.ndarray

    def thinned(self, samples: int) -> "PredictedPaths":
        """Every k-th sample, k the smallest that leaves at most `samples` (the last one kept)."""
        step = max(1, -(-len(self.times) // samples))
        keep = np.unique(np.append(np.arange(0, len(self.times), step), len(self.times) - 1))
        return PredictedPaths(self.times[keep], self.executed[keep], self.planned[keep], self.predicted[keep])

    def to_dict(self) -> dict[str, list]:
        return {name: np.round(getattr(self, name), 7).tolist() for name in ("times", "executed", "planned", "predicted")}

    @classmethod
    def from_dict(cls, data: dict[str, list]) -> "PredictedPaths":
        return cls(*(np.asarray(data[name], dtype=float) for name in ("times", "executed", "planned", "predicted")))


def predicted_paths(execution: Execution, model: TrackingModel) -> PredictedPaths:
    """`execution` against its plan and `model`'s prediction of it."""
    planned = np.column_stack([np.interp(execution.times, execution.reference_times, axis) for axis in execution.reference_positions.T])
    predicted = model.predict(execution.reference_times, execution.reference_positions, execution.times)
    return PredictedPaths(execution.times, execution.positions, planned, predicted)


def _rms(difference: np.ndarray) -> float:
    return float(np.sqrt(np.mean(difference**2)))


def used(model: TrackingModel, grasp: GraspModel | None = None) -> bool:
    """Whether method plan scores plans through `model` and `grasp`: when the robot departs
    from the plan by more than FOLLOWS_THE_PLAN on some axis and the model predicts better than
    the plan, or when it holds an object elsewhere than where it grasped it (`GraspModel.rigid`)."""
    departs = bool(np.max(model.plan_rms_) > FOLLOWS_THE_PLAN and model.kind_ != "plan")
    return departs or (grasp is not None and not grasp.rigid)


def execution_of(objective: SkillObjective, models: dict[str, HSMM], signals: SignalTable) -> Execution:
    """The reference of `models` (at the first placement) and the positions `signals` recorded."""
    reference = objective.reference(models)
    return Execution(reference.times, reference.positions, signals.times, np.column_stack([signals.columns[axis] for axis in "xyz"]))


@dataclass(frozen=True)
class RunTrackingRecord:
    """What `tracking.json` holds: the trials (0: the unoptimised skill) the models were fitted
    on, the tracking model, whether method plan scored its plans through them, and the grasp
    model (empty in runs recorded before objects' orientations were); `errors`, trial -> the
    RMS error (m) of the plan and of the model as predictions of its execution, and `best`, the
    best of those trials and its `PredictedPaths` (both absent from older runs' records)."""

    trials: list[int]
    model: TrackingModel
    used: bool
    grasp: GraspModel = field(default_factory=GraspModel)
    errors: dict[int, tuple[float, float]] = field(default_factory=dict)
    best: tuple[int, PredictedPaths] | None = None


def read_tracking(folder: Path) -> RunTrackingRecord | None:
    """The tracking model of the run in `folder` (its `tracking.json`), if it learned one."""
    path = Path(folder) / TRACKING_FILE
    if not path.is_file():
        return None
    try:
        data = json.loads(path.read_text())
        model, grasp = TrackingModel.from_dict(data), GraspModel.from_dict(data.get("grasp", {}))
        errors = {int(number): (float(error["plan"]), float(error["model"])) for number, error in data.get("errors", {}).items()}
        best = (int(data["best"]["trial"]), PredictedPaths.from_dict(data["best"])) if "best" in data else None
        return RunTrackingRecord([int(number) for number in data["trials"]], model, bool(data.get("used", used(model, grasp))), grasp, errors, best)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError, ValueError) as error:
        raise RunError(f"{path}: damaged ({getattr(error, 'msg', error)}); delete it and the next trial writes it anew") from None
