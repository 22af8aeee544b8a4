"""Demonstrations: a folder of signal CSVs, checked and resampled to one sample period."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from stl_lfd.errors import SignalError
from stl_lfd.signals import SignalTable, read_signal_csv

POSITION_COLUMNS = ("x", "y", "z")


def load_demos(folder: str | Path) -> list[SignalTable]:
    """Every `*.csv` of `folder`, sorted by name; each must have `t,x,y,z` and the same columns."""
    folder = Path(folder)
    if not folder.is_dir():
        raise SignalError(f"{folder}: no such folder of demonstrations")
    paths = sorted(folder.glob("*.csv"))
    if not paths:
        raise SignalError(f"{folder}: no demonstration CSV files in this folder")
    demos = [read_signal_csv(path, required=POSITION_COLUMNS) for path in paths]
    for demo in demos:
        if demo.samples < 2:
            raise SignalError(f"{demo.source}: a demonstration needs at least 2 samples (found {demo.samples})")
        if list(demo.columns) != list(demos[0].columns):
            raise SignalError(f"{demo.source}: columns {', '.join(demo.columns)} differ from {demos[0].source} ({', '.join(demos[0].columns)})")
    return demos


def median_period(demos: list[SignalTable]) -> float:
    return float(np.median(np.concatenate([np.diff(demo.times) for demo in demos])))


def resample(demo: SignalTable, period: float) -> np.ndarray:
    """`T x D` samples of `demo` every `period` seconds from its first sample (linear interpolation)."""
    times = demo.times[0] + np.arange(int(np.floor(demo.duration / period + 1e-9)) + 1) * period
    return np.column_stack([np.interp(times, demo.times, values) for values in demo.columns.values()])
