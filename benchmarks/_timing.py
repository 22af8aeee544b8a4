"""Shared helpers of the benchmarks: repeat-and-take-the-median timing, and the result table."""

from __future__ import annotations

import statistics
import time
from dataclasses import dataclass
from typing import Callable

from rich.console import Console
from rich.table import Table


def median_seconds(function: Callable[[], object], repeats: int = 7, number: int = 1) -> float:
    """Median wall time of `number` calls, over `repeats` runs, after one warm-up call."""
    function()
    runs = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(number):
            function()
        runs.append((time.perf_counter() - start) / number)
    return statistics.median(runs)


def paired_median_seconds(
    first: Callable[[], object], second: Callable[[], object], repeats: int = 9, numbers: tuple[int, int] = (1, 1)
) -> tuple[float, float]:
    """`median_seconds` of two functions timed in turns (`numbers` calls of each a turn), so
    that their ratio is taken under the same conditions on a machine whose speed varies."""
    first(), second()
    runs: tuple[list[float], list[float]] = ([], [])
    for _ in range(repeats):
        for function, number, times in zip((first, second), numbers, runs):
            start = time.perf_counter()
            for _ in range(number):
                function()
            times.append((time.perf_counter() - start) / number)
    return statistics.median(runs[0]), statistics.median(runs[1])


@dataclass
class Row:
    case: str
    size: str
    seconds: float
    target: float | None = None
    note: str = ""
    unit: str = "s"  # "MB" for a row that measures memory: `seconds` then holds megabytes

    @property
    def verdict(self) -> str:
        if self.target is None:
            return ""
        return "ok" if self.seconds <= self.target else "MISSED"


def format_seconds(seconds: float) -> str:
    if seconds < 1e-3:
        return f"{seconds * 1e6:.0f} us"
    if seconds < 1:
        return f"{seconds * 1e3:.2f} ms"
    return f"{seconds:.2f} s"


def print_table(title: str, rows: list[Row]) -> None:
    table = Table(title=title, title_justify="left")
    for column in ("case", "size", "time", "target", "", "note"):
        table.add_column(column, justify="right" if column in ("time", "target") else "left")
    for row in rows:
        shown = format_seconds if row.unit == "s" else lambda value: f"{value:.0f} {row.unit}"
        target = f"< {shown(row.target)}" if row.target is not None else ""
        table.add_row(row.case, row.size, shown(row.seconds), target, row.verdict, row.note)
    Console(width=130).print(table)
