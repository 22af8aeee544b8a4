"""Where a run's trials are recorded: one protocol (`RunStore`), implemented by a run directory
on disk (`directory.RunDirectory`), a run kept in memory (`MemoryRun`, for `optimize` from
Python), and both at once (`RecordedRun`)."""

from __future__ import annotations

from pathlib import Path
from typing import Protocol

from stl_lfd.hsmm import HSMM
from stl_lfd.optim.runs.directory import RunDirectory
from stl_lfd.optim.summary import Summary
from stl_lfd.optim.trials import Trial
from stl_lfd.signals import SignalTable, as_written


class RunStore(Protocol):
    """What the trial loop and `tell` record through.

    Attributes:
        path: the run directory (where executors exchange files), None for a run in memory.
    """

    path: Path | None

    def append_trial(self, trial: Trial, signals: SignalTable | None) -> None: ...

    def recorded_signals(self, trial: int) -> SignalTable | None: ...

    def write_best_models(self, models: dict[str, HSMM]) -> None: ...

    def has_best_models(self) -> bool: ...

    def write_summary(self, summary: Summary) -> None: ...

    def close(self) -> None: ...


class MemoryRun:
    """A run kept in memory: its trials, recorded signals (by trial number; 0 is the unoptimised
    skill) and best models."""

    path = None

    def __init__(self, initial_signals: SignalTable) -> None:
        self.signals: dict[int, SignalTable] = {0: initial_signals}
        self.trials: list[Trial] = []
        self.best_models: dict[str, HSMM] | None = None

    def append_trial(self, trial: Trial, signals: SignalTable | None) -> None:
        self.trials.append(trial)
        if signals is not None:
            self.signals[trial.trial] = signals

    def recorded_signals(self, trial: int) -> SignalTable | None:
        """The signals trial `trial` recorded (0: the unoptimised skill), None if it has none,
        to the digits a run directory keeps (so that a run in memory learns what a recorded
        one learns)."""
        signals = self.signals.get(trial)
        return as_written(signals) if signals is not None else None

    def write_best_models(self, models: dict[str, HSMM]) -> None:
        self.best_models = models

    def has_best_models(self) -> bool:
        return self.best_models is not None

    def write_summary(self, summary: Summary) -> None:
        """Nothing to keep: the loop returns the final summary."""

    def close(self) -> None:
        pass


class RecordedRun(MemoryRun):
    """A run kept in memory and recorded in its `RunDirectory` as well."""

    def __init__(self, initial_signals: SignalTable, disk: RunDirectory) -> None:
        super().__init__(initial_signals)
        self.disk = disk
        self.path = disk.path

    def append_trial(self, trial: Trial, signals: SignalTable | None) -> None:
        super().append_trial(trial, signals)
        self.disk.append_trial(trial, signals)

    def recorded_signals(self, trial: int) -> SignalTable | None:
        """As the run directory holds them, as a resumed run reads them."""
        return self.disk.recorded_signals(trial)

    def write_best_models(self, models: dict[str, HSMM]) -> None:
        super().write_best_models(models)
        self.disk.write_best_models(models)

    def write_summary(self, summary: Summary) -> None:
        self.disk.write_summary(summary)

    def close(self) -> None:
        self.disk.close()
