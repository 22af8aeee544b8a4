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
  inputs.json          the task file's own settings, the command-line overrides, and a
                       fingerprint of the files a resume reads (spec, behaviour, scene)
  executions/          with the command backend or ask/tell: per execution (initial/,
                       trial-NNNN/) the reference handed out, the signals that came back,
                       and the executor's stdout and stderr
  pending.json         the trial handed out by `stlopt ask` and not told yet
  .lock                held (advisory lock) by the process writing the run; names its PID
```

The directory appears complete (task, model, initial signals and summary) or not at all. A
trial's signals are on disk before its line is appended, every file but `trials.jsonl` is
replaced atomically, and a line cut short by a kill is dropped on resume: a killed run loses at
most the trial in flight.
"""

from __future__ import annotations

import fcntl
import json
import math
import os
import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from stl_lfd.errors import ConfigError, OutputError, RunError
from stl_lfd.files import check_output_folder, folder_mode, write_atomically
from stl_lfd.hsmm import HSMM, load_model, save_model
from stl_lfd.optim.loop import Trial, best_trial
from stl_lfd.optim.space import build_search_space
from stl_lfd.optim.summary import Summary
from stl_lfd.optim.task import SINGLE_SKILL, Task, load_task
from stl_lfd.poses import Pose
from stl_lfd.signals import SignalTable, write_signal_csv

TASK_FILE = "task.yaml"
MODEL_FILE = "model.npz"
BEST_MODEL_FILE = "best_model.npz"
TRIALS_FILE = "trials.jsonl"
SUMMARY_FILE = "summary.json"
SIGNALS_DIR = "signals"
INPUTS_FILE = "inputs.json"
PENDING_FILE = "pending.json"
DESIGN_FILE = "design.json"
LOCK_FILE = ".lock"


class RunDirectory:
    """Reads and writes one run directory (see the module docstring for its layout)."""

    def __init__(self, path: Path, lock: "RunLock | None" = None) -> None:
        self.path = Path(path)
        self.lock = lock

    @classmethod
    def create(
        cls, path: Path, task: Task, models: dict[str, HSMM], initial_signals: SignalTable, summary: Summary, inputs: dict[str, Any] | None = None
    ) -> "RunDirectory":
        """Write a new run directory in one step (built beside it, then renamed into place),
        locked for writing by this process."""
        with StagedRun(path) as staged:
            return staged.commit(task, models, initial_signals, summary, inputs)

    @classmethod
    def open(cls, path: Path, for_writing: bool = False) -> "RunDirectory":
        """An existing run directory; RunError when `path` is not one, or (`for_writing`)
        when another process is writing it."""
        path = Path(path)
        if not path.is_dir():
            raise RunError(f"{path}: no such run directory" if not path.exists() else f"{path}: is a file, not a run directory")
        awaiting_initial = not (path / SUMMARY_FILE).exists() and (path / PENDING_FILE).is_file()
        for name in (TASK_FILE, TRIALS_FILE) + (() if awaiting_initial else (SUMMARY_FILE,)):
            if not (path / name).is_file():
                raise RunError(f"{path}: not a run directory of stlopt optimize, or a damaged one (no {name})")
        if not list(path.glob("model*.npz")):
            raise RunError(f"{path}: not a run directory of stlopt optimize, or a damaged one (no {MODEL_FILE})")
        if not (path / SIGNALS_DIR).is_dir():
            raise RunError(f"{path}: a damaged run directory (its {SIGNALS_DIR}/ folder is missing)")
        return cls(path, RunLock.acquire(path, path) if for_writing else None)

    def close(self) -> None:
        """Release the write lock (if held); the kernel also releases it when the process ends."""
        if self.lock is not None:
            self.lock.release()
            self.lock = None

    def inputs(self) -> dict[str, Any] | None:
        """The record of the task file, overrides and input fingerprints (None for older runs)."""
        path = self.path / INPUTS_FILE
        if not path.exists():
            return None
        try:
            data = json.loads(path.read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
            raise RunError(f"{path}: damaged ({getattr(error, 'msg', error)})") from None
        if not isinstance(data, dict) or not {"task", "overrides", "fingerprint", "task_file"} <= set(data):
            raise RunError(f"{path}: damaged (expected the keys task_file, task, overrides, fingerprint)")
        return data

    def task(self) -> Task:
        return load_task(self.path / TASK_FILE)

    def models(self) -> dict[str, HSMM]:
        """The unoptimised skills by name (`skill` for a single-skill run)."""
        return _load_models(self.path, MODEL_FILE)

    def best_models(self) -> dict[str, HSMM]:
        return _load_models(self.path, BEST_MODEL_FILE)

    def summary(self) -> Summary:
        path = self.path / SUMMARY_FILE
        if not path.exists() and (self.path / PENDING_FILE).is_file():
            raise RunError(f"{self.path}: the run waits for the signals of its unoptimised skill (stlopt tell {self.path} SIGNALS.csv)")
        try:
            data = json.loads(path.read_text())
        except (OSError, UnicodeDecodeError) as error:
            raise RunError(f"{path}: cannot read ({error})") from None
        except json.JSONDecodeError as error:
            raise RunError(f"{path}:{error.lineno}: not valid JSON ({error.msg})") from None
        if not isinstance(data, dict) or not _finite(data.get("initial_robustness")):
            raise RunError(f"{path}: damaged (no finite 'initial_robustness')")
        try:
            return Summary.from_json(data)
        except (KeyError, TypeError) as error:
            raise RunError(f"{path}: damaged ({error})") from None

    def trials(self) -> list[Trial]:
        """The finished trials, checked: numbered 1, 2, ... and with finite values. A last line
        cut short by a kill is removed from the file; anything else damaged is a RunError."""
        path = self.path / TRIALS_FILE
        try:
            text = path.read_text()
        except (OSError, UnicodeDecodeError) as error:
            raise RunError(f"{path}: cannot read ({error})") from None
        lines = text.split("\n")
        complete, trials = [], []
        for number, line in enumerate(lines, start=1):
            if not line.strip():
                continue
            try:
                trial = _trial_from_json(json.loads(line))
            except (json.JSONDecodeError, KeyError, TypeError, ValueError, AttributeError):
                if number < len(lines) - 1 or text.endswith("\n"):  # a whole line: edited, not killed
                    raise RunError(f"{path}:{number}: damaged (not a trial record)") from None
                break
            problem = _trial_problem(trial, len(trials) + 1)
            if problem:
                raise RunError(f"{path}:{number}: damaged ({problem})")
            trials.append(trial)
            complete.append(line)
        if self.lock is not None and len(complete) != sum(1 for line in lines if line.strip()):
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

    def pending(self) -> "Pending | None":
        """The trial handed out by `stlopt ask` and not told yet, if any."""
        path = self.path / PENDING_FILE
        if not path.exists():
            return None
        try:
            data = json.loads(path.read_text())
            pending = Pending(int(data["trial"]), str(data["phase"]), None if data["x"] is None else np.array(data["x"], dtype=float),
                              float(data["optimizer_seconds"]), float(data["asked"]))  # fmt: skip
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError, ValueError) as error:
            raise RunError(f"{path}: damaged ({getattr(error, 'msg', error)}); delete it to ask again") from None
        if pending.trial < 0 or (pending.x is None) != (pending.trial == 0):
            raise RunError(f"{path}: damaged (trial {pending.trial}); delete it to ask again")
        return pending

    def write_pending(self, pending: "Pending") -> None:
        data = {"trial": pending.trial, "phase": pending.phase, "x": None if pending.x is None else [float(value) for value in pending.x],
                "optimizer_seconds": pending.optimizer_seconds, "asked": pending.asked}  # fmt: skip
        write_atomically(self.path / PENDING_FILE, json.dumps(data, indent=2) + "\n")

    def initial_design(self) -> np.ndarray | None:
        """The `M x d` initial (Sobol) points, if the run recorded them (runs asked for do)."""
        path = self.path / DESIGN_FILE
        if not path.exists():
            return None
        try:
            design = np.array(json.loads(path.read_text()), dtype=float)
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, TypeError, ValueError) as error:
            raise RunError(f"{path}: damaged ({getattr(error, 'msg', error)})") from None
        if design.ndim != 2:
            raise RunError(f"{path}: damaged (not a list of points)")
        return design

    def clear_pending(self) -> None:
        (self.path / PENDING_FILE).unlink(missing_ok=True)

    def signals_path(self, trial: int) -> Path:
        return self.path / SIGNALS_DIR / (f"trial-{trial:04d}.csv" if trial > 0 else "initial.csv")

    def write_best_models(self, models: dict[str, HSMM]) -> None:
        for skill, model in models.items():
            save_model(model, self.path / _model_file(BEST_MODEL_FILE, skill))

    def has_best_models(self) -> bool:
        return bool(list(self.path.glob("best_model*.npz")))

    def write_summary(self, summary: Summary) -> None:
        write_atomically(self.path / SUMMARY_FILE, json.dumps(summary.to_json(), indent=2) + "\n")


def _model_file(base: str, skill: str) -> str:
    """`model.npz` for the single skill, `model-NAME.npz` for a skill of a behaviour."""
    return base if skill == SINGLE_SKILL else base.replace(".npz", f"-{skill}.npz")


@dataclass(frozen=True)
class Pending:
    """A trial handed out by `stlopt ask`, waiting for its signals (`pending.json`).

    Attributes:
        trial: its number (0: the unoptimised skill).
        phase: what chose it (`sobol`, `stl`, ...; `initial` for trial 0).
        x: its point (None for trial 0).
        optimizer_seconds: time spent choosing it.
        asked: when it was handed out (seconds since the epoch).
    """

    trial: int
    phase: str
    x: np.ndarray | None
    optimizer_seconds: float
    asked: float


class StagedRun:
    """A run directory being built under a temporary name beside `path`, locked by this process.
    `commit` writes its files and renames it into place; leaving the `with` block without a
    commit removes it, so a run directory appears complete or not at all.

    Attributes:
        path: the temporary folder (where work done before the commit, such as the exchange
            folder of the unoptimised skill's execution, is written).
    """

    def __init__(self, destination: Path) -> None:
        self.destination = Path(destination)
        check_new_run_path(self.destination)
        try:
            self.destination.parent.mkdir(parents=True, exist_ok=True)
            self.path = Path(tempfile.mkdtemp(prefix=f".{self.destination.name}.", dir=self.destination.parent))
        except OSError as error:
            raise OutputError(f"{self.destination}: cannot create the run directory ({error.strerror or error})") from None
        self.committed = False
        try:
            self.path.chmod(folder_mode())  # mkdtemp makes it private; a run folder is an ordinary one
            self.lock: RunLock | None = RunLock.acquire(self.path, self.destination)
        except BaseException:
            shutil.rmtree(self.path, ignore_errors=True)
            raise

    def commit(
        self,
        task: Task,
        models: dict[str, HSMM],
        initial_signals: SignalTable | None,
        summary: Summary | None,
        inputs: dict[str, Any] | None = None,
        pending: Pending | None = None,
        design: np.ndarray | None = None,
    ) -> "RunDirectory":
        """Write the run's files and rename it into place. A run created by `stlopt ask` has no
        initial signals and summary yet, but the `pending` unoptimised skill and its initial
        `design` (`M x d`)."""
        staging = self.path
        run = RunDirectory(staging)
        write_atomically(staging / TASK_FILE, yaml.safe_dump(task.to_yaml_dict(), sort_keys=False))
        if inputs is not None:
            write_atomically(staging / INPUTS_FILE, json.dumps(inputs, indent=2) + "\n")
        for skill, model in models.items():
            save_model(model, staging / _model_file(MODEL_FILE, skill))
        (staging / SIGNALS_DIR).mkdir()
        if initial_signals is not None:
            write_signal_csv(initial_signals, staging / SIGNALS_DIR / "initial.csv")
        (staging / TRIALS_FILE).touch()
        if summary is not None:
            run.write_summary(summary)
        if pending is not None:
            run.write_pending(pending)
        if design is not None:
            write_atomically(staging / DESIGN_FILE, json.dumps([[float(value) for value in point] for point in design]) + "\n")
        if self.destination.exists():
            self.destination.rmdir()
        os.replace(staging, self.destination)
        self.committed = True
        lock, self.lock = self.lock, None
        return RunDirectory(self.destination, lock)

    def __enter__(self) -> "StagedRun":
        return self

    def __exit__(self, *exception: object) -> None:
        if not self.committed:
            if self.lock is not None:
                self.lock.release()
            shutil.rmtree(self.path, ignore_errors=True)


class RunLock:
    """An exclusive advisory lock (`flock`) on a run directory's `.lock`, which names the holder's
    PID. The kernel drops it when the process ends, however it ends."""

    def __init__(self, stream: Any) -> None:
        self.stream = stream

    @classmethod
    def acquire(cls, folder: Path, shown: Path) -> "RunLock":
        try:
            stream = open(folder / LOCK_FILE, "a+")
        except OSError as error:
            raise RunError(f"{shown}: cannot write to the run directory ({error.strerror or error})") from None
        try:
            fcntl.flock(stream.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            stream.seek(0)
            holder = stream.read().strip() or "unknown"
            stream.close()
            raise RunError(f"{shown}: the run is being written by another stlopt process (PID {holder}); wait for it to end or stop it") from None
        stream.seek(0)
        stream.truncate()
        stream.write(f"{os.getpid()}\n")
        stream.flush()
        return cls(stream)

    def release(self) -> None:
        if not self.stream.closed:
            fcntl.flock(self.stream.fileno(), fcntl.LOCK_UN)
            self.stream.close()


def check_new_run_path(path: Path) -> None:
    """Refuse, before any work, a run path that exists (and is not an empty folder) or cannot
    be created and written."""
    if path.exists() and (not path.is_dir() or any(path.iterdir())):
        raise RunError(f"{path}: the run directory exists; continue it with --resume or choose another with --out")
    check_output_folder(path, "run directory")


def _finite(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)


def _trial_problem(trial: Trial, expected_number: int) -> str:
    """What is wrong with a parsed trial record, or ''."""
    if trial.trial != expected_number:
        return f"trial {trial.trial} where trial {expected_number} was expected"
    if trial.status not in ("ok", "failed"):
        return f"status {trial.status!r}"
    if trial.robustness is not None and not math.isfinite(trial.robustness):
        return f"robustness {trial.robustness}"
    if (trial.robustness is None) != (trial.status == "failed"):
        return "a failed trial has a robustness, or a finished one has none"
    if trial.x.ndim != 1 or not np.all(np.isfinite(trial.x)):
        return "its point x is not a list of finite numbers"
    return ""


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
        **({"routes": trial.routes} if trial.routes else {}),
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
        routes=None if data.get("routes") is None else {str(k): float(v) for k, v in data["routes"].items()},
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
    placements: tuple[dict[str, Pose], ...] = ()


def trial_skill(path: Path, which: str = "best") -> TrialSkill:
    """The model of trial `which` (`best`, `initial`/`0`, or a trial number) of a run."""
    run = RunDirectory.open(path)
    task, models, trials = run.task(), run.models(), run.trials()
    if which == "best":
        best = best_trial(trials)
        number = best.trial if best is not None else 0
        if number == 0:
            raise RunError(f"{path}: the run has no successful trial yet; replay the unoptimised skill with --trial initial")
    elif which == "initial":
        number = 0
    else:
        number = _trial_number(which, len(trials), path)
    if number > 0:
        found = [trial for trial in trials if trial.trial == number]
        models = build_search_space(models, task.parameters, task.source).apply(models, found[0].x)
    return TrialSkill(number, models, task.behaviour, task.spec, task.scene, task.duration, task.semantics, task.nu, task.placements)


def _trial_number(which: str, finished: int, path: Path) -> int:
    """`--trial` as a number from 1 to the run's finished trials."""
    try:
        number = int(which)
    except ValueError:
        raise ConfigError(f"--trial must be 'best', 'initial' or a trial number (got {which!r})") from None
    if not 1 <= number <= finished:
        have = f"trials 1 to {finished}" if finished else "no finished trials"
        raise RunError(f"{path}: no trial {number} (the run has {have}; 'initial' is the unoptimised skill)")
    return number
