"""`StagedRun`: a new run directory built beside its destination and renamed into place, so
that it appears complete (task, models, initial signals, summary) or not at all."""

from __future__ import annotations

import glob
import json
import os
import re
import shutil
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from stl_lfd.errors import OutputError, StlLfdError
from stl_lfd.files import folder_mode, write_atomically
from stl_lfd.hsmm import HSMM, save_model
from stl_lfd.optim.runs.directory import DESIGN_FILE, INPUTS_FILE, MODEL_FILE, SIGNALS_DIR, TRIALS_FILE, RunDirectory, check_new_run_path, model_file
from stl_lfd.optim.runs.lock import LOCK_FILE, RunLock
from stl_lfd.optim.runs.records import Pending
from stl_lfd.optim.summary import Summary
from stl_lfd.optim.task import Task
from stl_lfd.signals import SignalTable, write_signal_csv

ABANDONED_AFTER = 5.0  # s: a staging folder this old and unlocked was left by a killed process (younger: its lock may not be taken yet)


def remove_abandoned(destination: Path) -> None:
    """Remove the staging folders of `destination` that killed processes left behind: named as
    `StagedRun` names them (`.NAME.` and `mkdtemp`'s 8 characters), holding a run's lock file,
    the lock free and untouched for `ABANDONED_AFTER` seconds. One being built is locked and
    kept, and any other hidden folder (`.NAME.backup`) is not ours."""
    pattern = re.compile(rf"\.{re.escape(destination.name)}\.[a-z0-9_]{{8}}")
    for folder in destination.parent.glob(f".{glob.escape(destination.name)}.*"):
        if not (pattern.fullmatch(folder.name) and folder.is_dir() and (folder / LOCK_FILE).is_file()):
            continue
        if time.time() - folder.stat().st_mtime < ABANDONED_AFTER:
            continue
        try:
            lock = RunLock.acquire(folder, folder)
        except StlLfdError:  # in use, or not ours to write
            continue
        lock.release()
        shutil.rmtree(folder, ignore_errors=True)


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
        remove_abandoned(self.destination)  # first: a rerun that finds the run made still tidies up
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
        run.write_task(task)
        if inputs is not None:
            write_atomically(staging / INPUTS_FILE, json.dumps(inputs, indent=2) + "\n")
        for skill, model in models.items():
            save_model(model, staging / model_file(MODEL_FILE, skill))
        (staging / SIGNALS_DIR).mkdir()
        if initial_signals is not None:
            write_signal_csv(initial_signals, staging / SIGNALS_DIR / "initial.csv")
        (staging / TRIALS_FILE).touch()
        if summary is not None:
            run.write_summary(summary)
        if pending is not None:
            run.write_pending([pending])
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

    def __exit__(self, kind: object, error: BaseException | None, trace: object) -> None:
        if not self.committed:
            if self.lock is not None:
                self.lock.release()
            shutil.rmtree(self.path, ignore_errors=True)
            if isinstance(error, StlLfdError) and error.args and str(self.path) in str(error.args[0]):
                error.args = (_without_paths_into(str(error.args[0]), self.path),) + error.args[1:]


def _without_paths_into(message: str, folder: Path) -> str:
    """`message` without the references to files in `folder`, which is gone (an executor's
    `(see .../stderr.txt)`): the message keeps what they said, and says nothing was created."""
    inside = re.escape(str(folder)) + r"[^)\s]*"
    message = re.sub(r" \(see " + inside + r"\)", "", message)
    message = re.sub(r" \(nothing on stderr: " + inside + r"\)", " (nothing on stderr)", message)
    return re.sub(inside, "(removed)", message) + "; the run directory was not created"
