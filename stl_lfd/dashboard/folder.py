"""The runs and sweeps under a folder, and each run as it grows, read without writing or locking.

A run directory is a folder holding `task.yaml`; a sweep folder holds `sweep.yaml` and its
runs in `runs/`. `RunView.refresh` costs a few `stat` calls when nothing changed, and reads
only the lines appended to `trials.jsonl` since the last refresh. Whatever it cannot read (a
half-written line, a file that is not JSON, a run directory that is not one) becomes the run's
`problem`, shown on the page: the dashboard never fails on a damaged run.
"""

from __future__ import annotations

import json
import math
import os
import time
from array import array
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from stl_lfd.files import UnreadableFile, read_text
from stl_lfd.optim.runs.directory import PENDING_FILE, SUMMARY_FILE, TASK_FILE, TRIALS_FILE, RunDirectory
from stl_lfd.optim.runs.lock import LOCK_FILE
from stl_lfd.optim.runs.trial_log import LongLine, TrialLog

SWEEP_FILE = "sweep.yaml"
SWEEP_RUNS = "runs"
WATCHED = (TASK_FILE, TRIALS_FILE, SUMMARY_FILE, PENDING_FILE, LOCK_FILE)  # a change to any is an update
MAX_DEPTH = 3  # how deep under the folder runs and sweeps are looked for
MAX_FILE_BYTES = 10_000_000  # task.yaml, summary.json, pending.json: a few kB each
MAX_LINE_BYTES = 1_000_000  # a trial's line in trials.jsonl: a few kB


@dataclass(frozen=True)
class Listing:
    """The run directories and sweep folders under a folder (a sweep's runs are its own)."""

    runs: tuple[Path, ...]
    sweeps: tuple[Path, ...]


def find(folder: Path, depth: int = MAX_DEPTH, root: Path | None = None) -> Listing:
    """The runs and sweeps under `folder` (itself included), sorted by path; a link that leads
    out of `root` (default: `folder`) is not followed."""
    root = Path(folder).resolve() if root is None else root
    if not inside(Path(folder), root):
        return Listing((), ())
    runs: list[Path] = []
    sweeps: list[Path] = []

    def visit(path: Path, level: int) -> None:
        if (path / SWEEP_FILE).is_file():
            sweeps.append(path)
        elif os.path.lexists(path / TASK_FILE):  # a run, damaged or not
            runs.append(path)
        elif level < depth:
            try:
                children = sorted(entry.path for entry in os.scandir(path) if entry.is_dir() and not entry.name.startswith("."))
            except OSError:
                return
            for child in children:
                if inside(Path(child), root):
                    visit(Path(child), level + 1)

    visit(Path(folder), 0)
    return Listing(tuple(sorted(runs)), tuple(sorted(sweeps)))


def inside(path: Path, root: Path) -> bool:
    """Whether `path`, once resolved (`..` and links), lies in the resolved folder `root`."""
    try:
        return path.resolve().is_relative_to(root)
    except (OSError, RuntimeError, ValueError):  # a loop of links, a NUL byte
        return False


def sweep_runs(sweep: Path, root: Path | None = None) -> list[Path]:
    """The finished cells of a sweep folder (a cell's run directory appears when complete), none
    of them through a link out of `root` (default: the sweep folder)."""
    return find(sweep / SWEEP_RUNS, depth=1, root=root if root is not None else Path(sweep).resolve()).runs


class TrialTable:
    """What the dashboard draws of a run's trials, kept compact (a run may have hundreds of
    thousands): the trial numbers, the robustness (NaN where a trial failed), the robustness of
    each part of the spec (NaN where a trial did not record it), and the last record whole."""

    def __init__(self) -> None:
        self.numbers = array("q")
        self.robustness = array("d")
        self.components: dict[str, array] = {}
        self.last: dict[str, Any] = {}

    def __len__(self) -> int:
        return len(self.numbers)

    def append(self, record: dict[str, Any]) -> None:
        """Add a trial: every value is converted first, so that a bad one adds nothing."""
        count = len(self.numbers)
        number = array("q", [record["trial"]])
        robustness = record.get("robustness")
        value = math.nan if robustness is None else float(robustness)
        parts = {name: float(part) if type(part) in (int, float) else math.nan for name, part in (record.get("components") or {}).items()}
        self.numbers.extend(number)
        self.robustness.append(value)
        for name in parts.keys() - self.components.keys():
            self.components[name] = array("d", [math.nan]) * count
        for name, column in self.components.items():
            column.append(parts.get(name, math.nan))
        self.last = record

    def best(self) -> tuple[int, float] | None:
        """The best trial's number and robustness (the first of equals), None before one scored."""
        values = np.array(self.robustness, dtype=float)  # a copy: another request may append meanwhile
        if not np.isfinite(values).any():
            return None
        index = int(np.nanargmax(np.where(np.isfinite(values), values, np.nan)))
        return self.numbers[index], float(values[index])


@dataclass
class RunView:
    """A run directory as the dashboard last read it.

    Attributes:
        trials: the trials of `trials.jsonl` read so far.
        summary: `summary.json`, or {} before it exists.
        task: `task.yaml`, or {}.
        pending: the entries of `pending.json` (trials handed out and not recorded).
        problem: what is wrong with the run directory ("" when nothing).
        version: grows by one at every refresh that found a change.
    """

    path: Path
    trials: TrialTable = field(default_factory=TrialTable)
    summary: dict[str, Any] = field(default_factory=dict)
    task: dict[str, Any] = field(default_factory=dict)
    pending: list[dict[str, Any]] = field(default_factory=list)
    problem: str = ""
    version: int = 0
    task_version: int = 0  # grows when task.yaml is read (again: another run moved in)
    _log: TrialLog = field(init=False)
    _stamp: tuple = ()

    def __post_init__(self) -> None:
        self._log = TrialLog(self.path / TRIALS_FILE, MAX_LINE_BYTES)

    def refresh(self) -> bool:
        """Read what changed since the last refresh; whether anything did. Whatever is wrong
        with the files becomes `problem`: a damaged run never raises here."""
        stamp = tuple(_stat(self.path / name) for name in WATCHED)
        if stamp == self._stamp and self.version > 0:
            return False
        if self._stamp and self._moved_in(stamp):
            self.task, self.trials, self._log = {}, TrialTable(), TrialLog(self.path / TRIALS_FILE, MAX_LINE_BYTES)
        self._stamp = stamp
        self.problem = ""
        try:
            self._read()
        except RecursionError:
            self.problem = "a file nests too deeply to read"
        except Exception as error:  # a damaged file of any kind: the page says what it can
            self.problem = str(error) or type(error).__name__
        self.version += 1
        return True

    def _moved_in(self, stamp: tuple) -> bool:
        """Whether another run moved in since the last refresh: task.yaml changed, or
        trials.jsonl is another file (`_stat`: size, mtime, inode) or shorter than what was read."""
        (task, trials), (old_task, old_trials) = stamp[:2], self._stamp[:2]
        return task != old_task or trials[2] != old_trials[2] or trials[0] < self._log.offset

    def _read(self) -> None:
        if not self.task:
            self.task = _mapping(yaml.safe_load(_text(self.path / TASK_FILE)), TASK_FILE)
            self.task_version += 1
        self.summary = _json_file(self.path / SUMMARY_FILE, {})
        pending = _json_file(self.path / PENDING_FILE, {"pending": []})
        entries = pending.get("pending", []) if "pending" in pending else [pending]
        if not isinstance(entries, list) or not all(isinstance(entry, dict) for entry in entries):
            raise ValueError(f"{PENDING_FILE}: not a list of pending trials")
        self.pending = entries
        if not isinstance(self.task.get("optimizer") or {}, dict):
            raise ValueError(f"{TASK_FILE}: 'optimizer' is not a mapping")
        self._read_new_trials()

    def _read_new_trials(self) -> None:
        """Append the complete lines written since the last read (a line still being written
        waits for the next refresh)."""
        try:
            for line in self._log.read_new():
                if not _is_trial_record(line.record):
                    raise ValueError(f"{TRIALS_FILE} line {line.number}: not a trial record")
                self.trials.append(line.record)
        except FileNotFoundError:
            raise ValueError(f"{TRIALS_FILE}: missing") from None
        except (IsADirectoryError, UnreadableFile):
            raise ValueError(f"{TRIALS_FILE}: not a regular file") from None
        except LongLine as error:
            raise ValueError(f"{TRIALS_FILE} {error}") from None

    @property
    def name(self) -> str:
        return str(self.task.get("name") or self.path.name)

    @property
    def method(self) -> str:
        optimizer = self.task.get("optimizer")
        return str(optimizer.get("method", "-")) if isinstance(optimizer, dict) else "-"

    @property
    def budget(self) -> int | None:
        optimizer = self.task.get("optimizer")
        budget = self.summary.get("budget") or (optimizer.get("trials") if isinstance(optimizer, dict) else None)
        return int(budget) if isinstance(budget, (int, float)) else None

    def best(self) -> tuple[int, float] | None:
        """The best trial's number and robustness, None before a trial scored."""
        return self.trials.best()

    def writer(self) -> int | None:
        """The PID of the stlopt process writing the run, if one is: the holder of the lock on
        its `.lock` file (`RunLock`), as the kernel lists it, never taken here."""
        try:
            status = (self.path / LOCK_FILE).stat()
        except OSError:
            return None
        return held_locks().get((os.major(status.st_dev), os.minor(status.st_dev), status.st_ino))

    def state(self) -> str:
        """`damaged: ...`, `running`, `waiting for tell: trial N`, `finished` or `stopped after N
        of M trials` (with the error of its last trial when that one failed)."""
        if self.problem:
            return f"damaged: {self.problem}"
        if self.writer() is not None:
            return "running"
        waiting = [entry for entry in self.pending if not entry.get("told")]
        if waiting:
            return "waiting for tell: " + ", ".join(f"trial {entry.get('trial')}" + (f" ({entry['robot']})" if entry.get("robot") else "") for entry in waiting)
        if self.summary.get("complete"):
            return "finished"
        stopped = f"stopped after {len(self.trials)} of {self.budget} trials" if self.budget else "stopped"
        last = self.trials.last
        return stopped + (f"; trial {last['trial']} failed: {last.get('error') or 'no reason recorded'}" if last.get("status") == "failed" else "")

    def signals_path(self, trial: int) -> Path:
        return RunDirectory(self.path).signals_path(trial)

    def spec_path(self) -> Path | None:
        spec = self.task.get("spec")
        return (self.path / spec).resolve() if isinstance(spec, str) else None


_locks: tuple[float, dict[tuple[int, int, int], int]] = (0.0, {})


def held_locks(max_age: float = 0.2) -> dict[tuple[int, int, int], int]:
    """(device major, minor, inode) -> PID of every `flock` lock held on this machine, from
    Linux's /proc/locks (read at most every `max_age` seconds); empty elsewhere."""
    global _locks
    if time.monotonic() - _locks[0] > max_age:
        held = {}
        try:
            lines = Path("/proc/locks").read_text().splitlines()
        except OSError:
            lines = []
        for line in lines:
            fields = line.split()
            if len(fields) > 5 and fields[1] == "FLOCK" and fields[4].isdigit():
                major, minor, inode = fields[5].split(":")
                held[(int(major, 16), int(minor, 16), int(inode))] = int(fields[4])
        _locks = (time.monotonic(), held)
    return _locks[1]


def _is_trial_record(record: Any) -> bool:
    """What the dashboard reads of a trial record is there and of its type."""
    if not isinstance(record, dict) or type(record.get("trial")) is not int:
        return False
    robustness, components = record.get("robustness"), record.get("components")
    return (robustness is None or type(robustness) in (int, float)) and (components is None or isinstance(components, dict))


def _stat(path: Path) -> tuple[int, int, int]:
    try:
        status = path.stat()
    except OSError:
        return (-1, -1, -1)
    return (status.st_size, status.st_mtime_ns, status.st_ino)


def _text(path: Path) -> str:
    """The text of one of a run's small files, at most `MAX_FILE_BYTES`."""
    try:
        return read_text(path, path.name, MAX_FILE_BYTES)
    except UnreadableFile as error:
        raise ValueError(f"{path.name}: {error}") from None


def _json_file(path: Path, missing: dict[str, Any]) -> dict[str, Any]:
    if not os.path.lexists(path):
        return missing
    try:
        return _mapping(json.loads(_text(path)), path.name)
    except json.JSONDecodeError as error:
        raise ValueError(f"{path.name} line {error.lineno}: not JSON ({error.msg})") from None


def _mapping(data: Any, name: str) -> dict[str, Any]:
    if not isinstance(data, dict):
        raise ValueError(f"{name}: not a mapping")
    return data


def age(seconds_since_epoch: float) -> str:
    """`5 s ago`, `3 min ago`, `2 h ago`."""
    elapsed = max(0.0, time.time() - seconds_since_epoch)
    return f"{elapsed:.0f} s ago" if elapsed < 120 else f"{elapsed / 60:.0f} min ago" if elapsed < 7200 else f"{elapsed / 3600:.0f} h ago"
