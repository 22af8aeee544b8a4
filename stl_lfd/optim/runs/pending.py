"""The trials `stlopt ask` handed out and that are not recorded yet (`pending.json`): one per
robot, as many at once as the task's `optimizer.workers`.

A trial told before the trials handed out ahead of it waits here, scored, its signals already
in the run's signals/ folder, and is recorded as soon as they are: `trials.jsonl` holds trials
1, 2, ... in order, whatever order they were told in. Each trial's point depends only on the
trials before its batch and the points still pending (`loop.next_points`, as with parallel
workers), so a fleet's run is the run `stlopt optimize --workers` makes with the same seed.
"""

from __future__ import annotations

import time
from dataclasses import replace
from pathlib import Path
from typing import Any

from stl_lfd.errors import RunError
from stl_lfd.optim.runs.directory import SUMMARY_FILE, RunDirectory
from stl_lfd.optim.runs.recorder import Recorder
from stl_lfd.optim.runs.records import Pending
from stl_lfd.optim.trials import Trial
from stl_lfd.signals import write_signal_csv
from stl_lfd.sim import exchange_folder
from stl_lfd.spelling import spelled


def live_pending(run: RunDirectory) -> list[Pending]:
    """The pending trials, without those a tell killed after recording them left behind."""
    entries = run.pending()
    recorded = len(run.trials())
    live = [entry for entry in entries if not (entry.trial == 0 and (run.path / SUMMARY_FILE).exists()) and not 0 < entry.trial <= recorded]
    if len(live) != len(entries):
        run.write_pending(live)
    return live


def handed_out(entries: list[Pending]) -> str:
    """`trial 3 to robot a, trial 4 to robot b`: the pending trials not told yet, for messages."""
    return ", ".join(f"trial {entry.trial} to {entry.holder}" for entry in entries if entry.told is None)


def still_out(run_path: Path) -> str:
    """The trials of the run in `run_path` handed out and not told yet, for messages ('' if none)."""
    return handed_out(RunDirectory(Path(run_path)).pending())


def to_tell(entries: list[Pending], run_path: Path, trial: int | None, signals: Path | None) -> Pending:
    """The pending trial a tell is about: trial number `trial`; else the one whose exchange
    folder holds `signals`; else the only one not told yet.

    Raises:
        RunError: none is pending, `trial` is not, or several are and nothing says which.
    """
    untold = [entry for entry in entries if entry.told is None]
    if not untold:
        raise RunError(f"{run_path}: no trial is pending; hand out the next one with: stlopt ask {run_path}")
    if trial is not None:
        chosen = next((entry for entry in untold if entry.trial == trial), None)
        if chosen is None:
            raise RunError(f"{run_path}: trial {trial} is not waiting to be told (handed out: {handed_out(entries)})")
        return chosen
    if signals is not None:
        folder = Path(signals).resolve().parent
        chosen = next((entry for entry in untold if exchange_folder(run_path, entry.trial).resolve() == folder), None)
        if chosen is not None:
            return chosen
    if len(untold) > 1:
        raise RunError(f"{run_path}: several trials are handed out ({handed_out(entries)}); say which with {spelled('trial')} N")
    return untold[0]


def complete(run: RunDirectory, recorder: Recorder, entries: list[Pending], trial: Trial, signals: Any, handed: Pending | None = None) -> list[Pending]:
    """Record `trial` (told, or refused before it was handed out) when every trial before it is
    recorded, then the told trials that waited for it; otherwise keep it waiting, told. Returns
    the trials still pending (and writes them)."""
    entries = [entry for entry in entries if entry.trial != trial.trial]
    if trial.trial == len(recorder.history) + 1:
        recorder.record(trial, signals, trial.wall_seconds)
        entries = recorded_in_turn(recorder, entries)
    else:
        if signals is not None:
            write_signal_csv(signals, run.signals_path(trial.trial))
        handed = handed or Pending(trial.trial, trial.phase, trial.x, trial.optimizer_seconds, time.time())
        entries = sorted([*entries, replace(handed, told=trial)], key=lambda entry: entry.trial)
    run.write_pending(entries)
    return entries


def recorded_in_turn(recorder: Recorder, entries: list[Pending]) -> list[Pending]:
    """Record the told trials that come next (their signals are in place); the rest stay."""
    while entries and entries[0].told is not None and entries[0].trial == len(recorder.history) + 1:
        recorder.record(entries[0].told, None, entries[0].told.wall_seconds)
        entries = entries[1:]
    return entries
