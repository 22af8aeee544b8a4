"""Run directories: everything an optimisation run writes, written so that nothing is lost.

```
runs/<name>/
  task.yaml            the task as used (absolute paths, command-line overrides applied)
  model.npz            the unoptimised skill model (model-NAME.npz per skill of a behaviour)
  trials.jsonl         one JSON line per finished trial, appended and flushed to disk
  signals/initial.csv  the recorded signals of the unoptimised skill
  signals/trial-NNNN.csv  the recorded signals of each successful trial
  best_model.npz       the model of the best trial so far (best_model-NAME.npz per skill)
  summary.json         initial and best robustness, best trial, counts, wall time
```

The directory appears complete (task, model, initial signals and summary) or not at all. A
trial's signals are on disk before its line is appended, every file but `trials.jsonl` is
replaced atomically, and a line cut short by a kill is dropped on resume: a killed run loses at
most the trial in flight.
"""

from __future__ import annotations

import json
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from stl_lfd.errors import ConfigError
from stl_lfd.hsmm import HSMM, load_model, save_model
from stl_lfd.optim.loop import Trial
from stl_lfd.optim.space import build_search_space
from stl_lfd.optim.task import SINGLE_SKILL, Task, load_task
from stl_lfd.signals import SignalTable, write_atomically, write_signal_csv

TASK_FILE = "task.yaml"
MODEL_FILE = "model.npz"
BEST_MODEL_FILE = "best_model.npz"
TRIALS_FILE = "trials.jsonl"
SUMMARY_FILE = "summary.json"
SIGNALS_DIR = "signals"


class RunDirectory:
    """Reads and writes one run directory (see the module docstring for its layout)."""

    def __init__(self, path: Path) -> None:
        self.path = Path(path)

    @classmethod
    def create(cls, path: Path, task: Task, models: dict[str, HSMM], initial_signals: SignalTable, summary: dict[str, Any]) -> "RunDirectory":
        """Write a new run directory in one step (built beside it, then renamed into place)."""
        path = Path(path)
        if path.exists() and (not path.is_dir() or any(path.iterdir())):
            raise ConfigError(f"{path}: the run directory exists; continue it with --resume or choose another with --out")
        path.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(prefix=f".{path.name}.", dir=path.parent))
        try:
            run = cls(staging)
            write_atomically(staging / TASK_FILE, yaml.safe_dump(task.to_yaml_dict(), sort_keys=False))
            for skill, model in models.items():
                save_model(model, staging / _model_file(MODEL_FILE, skill))
            (staging / SIGNALS_DIR).mkdir()
            write_signal_csv(initial_signals, staging / SIGNALS_DIR / "initial.csv")
            (staging / TRIALS_FILE).touch()
            run.write_summary(summary)
            if path.exists():
                path.rmdir()
            os.replace(staging, path)
        except BaseException:
            shutil.rmtree(staging, ignore_errors=True)
            raise
        return cls(path)

    @classmethod
    def open(cls, path: Path) -> "RunDirectory":
        """An existing run directory; ConfigError when `path` is not one."""
        path = Path(path)
        for name in (TASK_FILE, TRIALS_FILE, SUMMARY_FILE):
            if not (path / name).is_file():
                raise ConfigError(f"{path}: not a run directory of stlopt optimize (no {name})")
        if not list(path.glob("model*.npz")):
            raise ConfigError(f"{path}: not a run directory of stlopt optimize (no {MODEL_FILE})")
        return cls(path)

    def task(self) -> Task:
        return load_task(self.path / TASK_FILE)

    def models(self) -> dict[str, HSMM]:
        """The unoptimised skills by name (`skill` for a single-skill run)."""
        return _load_models(self.path, MODEL_FILE)

    def best_models(self) -> dict[str, HSMM]:
        return _load_models(self.path, BEST_MODEL_FILE)

    def summary(self) -> dict[str, Any]:
        try:
            return json.loads((self.path / SUMMARY_FILE).read_text())
        except json.JSONDecodeError as error:
            raise ConfigError(f"{self.path / SUMMARY_FILE}: not valid JSON ({error.msg})") from None

    def trials(self) -> list[Trial]:
        """The finished trials; a last line cut short by a kill is removed from the file."""
        path = self.path / TRIALS_FILE
        text = path.read_text()
        lines = text.split("\n")
        complete, trials = [], []
        for number, line in enumerate(lines, start=1):
            if not line.strip():
                continue
            try:
                trials.append(_trial_from_json(json.loads(line)))
            except (json.JSONDecodeError, KeyError, TypeError):
                if number < len(lines) - 1:  # not the last line: the file was edited, not killed
                    raise ConfigError(f"{path}:{number}: not a trial record") from None
                break
            complete.append(line)
        if len(complete) != sum(1 for line in lines if line.strip()):
            write_atomically(path, "".join(line + "\n" for line in complete))
        return trials

    def append_trial(self, trial: Trial, signals: SignalTable | None) -> None:
        """Record a finished trial: its signals first, then its line, flushed to disk."""
        if signals is not None:
            write_signal_csv(signals, self.signals_path(trial.trial))
        with open(self.path / TRIALS_FILE, "a") as stream:
            stream.write(json.dumps(_trial_to_json(trial)) + "\n")
            stream.flush()
            os.fsync(stream.fileno())

    def signals_path(self, trial: int) -> Path:
        return self.path / SIGNALS_DIR / (f"trial-{trial:04d}.csv" if trial > 0 else "initial.csv")

    def write_best_models(self, models: dict[str, HSMM]) -> None:
        for skill, model in models.items():
            save_model(model, self.path / _model_file(BEST_MODEL_FILE, skill))

    def has_best_models(self) -> bool:
        return bool(list(self.path.glob("best_model*.npz")))

    def write_summary(self, summary: dict[str, Any]) -> None:
        write_atomically(self.path / SUMMARY_FILE, json.dumps(summary, indent=2) + "\n")


def _model_file(base: str, skill: str) -> str:
    """`model.npz` for the single skill, `model-NAME.npz` for a skill of a behaviour."""
    return base if skill == SINGLE_SKILL else base.replace(".npz", f"-{skill}.npz")


def _load_models(folder: Path, base: str) -> dict[str, HSMM]:
    single = folder / base
    if single.exists():
        return {SINGLE_SKILL: load_model(single)}
    prefix = base.replace(".npz", "-")
    return {path.stem[len(prefix) :]: load_model(path) for path in sorted(folder.glob(f"{prefix}*.npz"))}


def _trial_to_json(trial: Trial) -> dict[str, Any]:
    return {
        "trial": trial.trial,
        "phase": trial.phase,
        "robustness": trial.robustness,
        "satisfied": trial.satisfied,
        "status": trial.status,
        "error": trial.error,
        "wall_seconds": round(trial.wall_seconds, 4),
        "optimizer_seconds": round(trial.optimizer_seconds, 4),
        "rollout_seconds": round(trial.rollout_seconds, 4),
        "parameters": trial.parameters,
        "components": trial.components,
        "x": [float(value) for value in trial.x],
    }


def _trial_from_json(data: dict[str, Any]) -> Trial:
    return Trial(
        trial=int(data["trial"]),
        phase=str(data["phase"]),
        x=np.array(data["x"], dtype=float),
        robustness=None if data["robustness"] is None else float(data["robustness"]),
        status=str(data["status"]),
        error=data.get("error"),
        optimizer_seconds=float(data.get("optimizer_seconds", 0.0)),
        rollout_seconds=float(data.get("rollout_seconds", 0.0)),
        parameters=dict(data.get("parameters", {})),
        components=None if data.get("components") is None else {str(k): float(v) for k, v in data["components"].items()},
    )


@dataclass(frozen=True)
class TrialSkill:
    """The models of one trial of a run, with the run's settings (for `stlopt replay`)."""

    trial: int
    models: dict[str, HSMM]
    behaviour: Path | None
    spec: Path
    scene: str
    duration: float
    semantics: str
    nu: float


def trial_skill(path: Path, which: str = "best") -> TrialSkill:
    """The model of trial `which` (`best`, `initial`/`0`, or a trial number) of a run."""
    run = RunDirectory.open(path)
    task, models, trials = run.task(), run.models(), run.trials()
    if which == "best":
        number = run.summary().get("best_trial") or 0
    elif which == "initial":
        number = 0
    else:
        try:
            number = int(which)
        except ValueError:
            raise ConfigError(f"--trial must be 'best', 'initial' or a trial number (got {which!r})") from None
    if number > 0:
        found = [trial for trial in trials if trial.trial == number]
        if not found:
            raise ConfigError(f"{path}: no trial {number} (the run has {len(trials)} finished trials)")
        models = build_search_space(models, task.parameters, task.source).apply(models, found[0].x)
    return TrialSkill(number, models, task.behaviour, task.spec, task.scene, task.duration, task.semantics, task.nu)
