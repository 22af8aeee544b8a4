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

import json
import os
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from stl_lfd.errors import RunError
from stl_lfd.files import UnreadableFile, check_output_folder, write_atomically
from stl_lfd.hsmm import HSMM, load_model, save_model
from stl_lfd.optim.runs.lock import RunLock
from stl_lfd.optim.runs.records import Pending, finite, trial_from_json, trial_problem, trial_to_json
from stl_lfd.optim.runs.trial_log import TrialLog, decoded
from stl_lfd.optim.settings import SINGLE_SKILL
from stl_lfd.optim.summary import Summary
from stl_lfd.optim.task import Task, load_task
from stl_lfd.optim.trials import Trial
from stl_lfd.signals import SignalTable, read_signal_csv, write_signal_csv
from stl_lfd.spelling import spelled

TASK_FILE = "task.yaml"
MODEL_FILE = "model.npz"
BEST_MODEL_FILE = "best_model.npz"
TRIALS_FILE = "trials.jsonl"
SUMMARY_FILE = "summary.json"
SIGNALS_DIR = "signals"
INPUTS_FILE = "inputs.json"
PENDING_FILE = "pending.json"
DESIGN_FILE = "design.json"


class RunDirectory:
    """Reads and writes one run directory (see the module docstring for its layout)."""

    def __init__(self, path: Path, lock: "RunLock | None" = None) -> None:
        self.path = Path(path)
        self.lock = lock

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
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError) as error:
            raise RunError(f"{path}: damaged ({_why(error)})") from None
        if not isinstance(data, dict) or not {"task", "overrides", "fingerprint", "task_file"} <= set(data):
            raise RunError(f"{path}: damaged (expected the keys task_file, task, overrides, fingerprint)")
        return data

    def task(self) -> Task:
        return load_task(self.path / TASK_FILE)

    def write_task(self, task: Task) -> None:
        """Replace the run's task (a new budget of trials)."""
        write_atomically(self.path / TASK_FILE, yaml.safe_dump(task.to_yaml_dict(), sort_keys=False))

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
        except RecursionError as error:
            raise RunError(f"{path}: damaged ({_why(error)})") from None
        if not isinstance(data, dict) or not finite(data.get("initial_robustness")):
            raise RunError(f"{path}: damaged (no finite 'initial_robustness')")
        try:
            return Summary.from_json(data)
        except (KeyError, TypeError) as error:
            raise RunError(f"{path}: damaged ({error})") from None

    def trials(self) -> list[Trial]:
        """The finished trials, checked: numbered 1, 2, ... and with finite values. A last line
        cut short by a kill is removed from the file (one whole but for its newline is kept and
        ended); anything else damaged is a RunError."""
        path = self.path / TRIALS_FILE
        log = TrialLog(path)
        trials: list[Trial] = []
        try:
            for line in log.read_new():
                trials.append(self._checked(line.record, line.number, len(trials) + 1))
        except (OSError, UnreadableFile) as error:
            raise RunError(f"{path}: cannot read ({error})") from None
        if not log.tail.strip():
            return trials
        record = decoded(log.tail)  # None: cut short (a prefix of a JSON object is never JSON)
        last = None if record is None else self._checked(record, log.lines + 1, len(trials) + 1)
        if self.lock is not None:  # the next trial's line starts on a line of its own
            with open(path, "r+b") as stream:
                stream.truncate(log.offset + len(log.tail) if last else log.offset)
                stream.seek(0, os.SEEK_END)
                stream.write(b"\n" if last else b"")
                os.fsync(stream.fileno())
        return trials + ([last] if last else [])

    def _checked(self, record: Any, number: int, expected: int) -> Trial:
        """The trial of line `number` of trials.jsonl, which should be trial `expected`."""
        where = f"{self.path / TRIALS_FILE}:{number}"
        try:
            trial = trial_from_json(record)
        except (KeyError, TypeError, ValueError, AttributeError, RecursionError):
            raise RunError(f"{where}: damaged (not a trial record)") from None
        problem = trial_problem(trial, expected)
        if problem:
            raise RunError(f"{where}: damaged ({problem})")
        return trial

    def append_trial(self, trial: Trial, signals: SignalTable | None) -> None:
        """Record a finished trial: its signals first, then its line, flushed to disk."""
        if signals is not None:
            write_signal_csv(signals, self.signals_path(trial.trial))
        with open(self.path / TRIALS_FILE, "a") as stream:
            stream.write(json.dumps(trial_to_json(trial)) + "\n")
            stream.flush()
            os.fsync(stream.fileno())

    def recorded_signals(self, trial: int) -> SignalTable | None:
        """The signals trial `trial` recorded (0: the unoptimised skill), None if it has none."""
        path = self.signals_path(trial)
        return read_signal_csv(path) if path.is_file() else None

    def pending(self) -> list[Pending]:
        """The trials handed out by `stlopt ask` and not recorded yet, in trial order (a run
        recorded before several could be pending holds one, as a single record)."""
        path = self.path / PENDING_FILE
        if not path.exists():
            return []
        try:
            data = json.loads(path.read_text())
            entries = [Pending.from_json(item) for item in (data["pending"] if "pending" in data else [data])]
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, KeyError, TypeError, ValueError, RecursionError) as error:
            raise RunError(f"{path}: damaged ({_why(error)}); delete it to ask again") from None
        for pending in entries:
            if pending.trial < 0 or (pending.x is None) != (pending.trial == 0) or (pending.told is not None and pending.told.trial != pending.trial):
                raise RunError(f"{path}: damaged (trial {pending.trial}); delete it to ask again")
        return sorted(entries, key=lambda pending: pending.trial)

    def write_pending(self, entries: list[Pending]) -> None:
        """Keep `entries` as the pending trials (none: the file goes)."""
        if not entries:
            self.clear_pending()
            return
        write_atomically(self.path / PENDING_FILE, json.dumps({"pending": [pending.to_json() for pending in entries]}, indent=2) + "\n")

    def initial_design(self) -> np.ndarray | None:
        """The `M x d` initial (Sobol) points, if the run recorded them (runs asked for do)."""
        path = self.path / DESIGN_FILE
        if not path.exists():
            return None
        try:
            design = np.array(json.loads(path.read_text()), dtype=float)
        except (OSError, UnicodeDecodeError, json.JSONDecodeError, TypeError, ValueError, RecursionError) as error:
            raise RunError(f"{path}: damaged ({_why(error)})") from None
        if design.ndim != 2:
            raise RunError(f"{path}: damaged (not a list of points)")
        return design

    def clear_pending(self) -> None:
        (self.path / PENDING_FILE).unlink(missing_ok=True)

    def missing_signals(self) -> list[Path]:
        """The signal files the run should hold and does not: the unoptimised skill's (once it
        has a summary) and each successful trial's."""
        expected = ([0] if (self.path / SUMMARY_FILE).is_file() else []) + [trial.trial for trial in self.trials() if trial.status == "ok"]
        return [path for path in map(self.signals_path, expected) if not path.is_file()]

    def signals_path(self, trial: int) -> Path:
        return self.path / SIGNALS_DIR / (f"trial-{trial:04d}.csv" if trial > 0 else "initial.csv")

    def write_best_models(self, models: dict[str, HSMM]) -> None:
        for skill, model in models.items():
            save_model(model, self.path / model_file(BEST_MODEL_FILE, skill))

    def has_best_models(self) -> bool:
        return bool(list(self.path.glob("best_model*.npz")))

    def write_summary(self, summary: Summary) -> None:
        write_atomically(self.path / SUMMARY_FILE, json.dumps(summary.to_json(), indent=2) + "\n")


def _why(error: Exception) -> str:
    """What a damaged record's reading error says, in a few words."""
    if isinstance(error, RecursionError):
        return "it nests too deeply"
    return str(getattr(error, "msg", error))


def model_file(base: str, skill: str) -> str:
    """`model.npz` for the single skill, `model-NAME.npz` for a skill of a behaviour."""
    return base if skill == SINGLE_SKILL else base.replace(".npz", f"-{skill}.npz")


def check_new_run_path(path: Path) -> None:
    """Refuse, before any work, a run path that exists (and is not an empty folder) or cannot
    be created and written."""
    if path.exists() and not path.is_dir():
        raise RunError(f"{path}: is a file, not a run directory; choose another with {spelled('out')}")
    if path.exists() and any(path.iterdir()):
        raise RunError(f"{path}: the run directory exists; continue it with {spelled('resume')} or choose another with {spelled('out')}")
    check_output_folder(path, "run directory")


def _load_models(folder: Path, base: str) -> dict[str, HSMM]:
    single = folder / base
    if single.exists():
        return {SINGLE_SKILL: load_model(single)}
    prefix = base.replace(".npz", "-")
    return {path.stem[len(prefix) :]: load_model(path) for path in sorted(folder.glob(f"{prefix}*.npz"))}
