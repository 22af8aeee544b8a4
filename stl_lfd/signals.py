"""Signal CSV files: a header row, a time column `t` (s, strictly increasing) and one column per
signal. Rollouts write them, `stlopt robustness` and the skill learner read them.
"""

from __future__ import annotations

import csv
import io
import math
import sys
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import TextIO

import numpy as np

from stl_lfd.errors import SignalError
from stl_lfd.files import MAX_TEXT_BYTES, UnreadableFile, decoded, read_text, write_atomically

TIME_COLUMN = "t"


@dataclass
class SignalTable:
    """One recorded trace.

    Attributes:
        times: `T` sample times in seconds.
        columns: signal name -> `T` array (the time column excluded).
        source: where the table came from, for messages.
    """

    times: np.ndarray
    columns: dict[str, np.ndarray]
    source: str = field(default="<memory>")

    @property
    def samples(self) -> int:
        return int(self.times.size)

    @property
    def duration(self) -> float:
        return float(self.times[-1] - self.times[0]) if self.samples else 0.0


def read_signal_csv(path: str | Path, required: tuple[str, ...] = ()) -> SignalTable:
    """Read a signal CSV; `-` reads standard input.

    Args:
        path: file path or "-".
        required: signal columns that must be present besides `t`.

    Raises:
        SignalError: naming the file, and the line and column of a bad cell.
    """
    shown = "<stdin>" if str(path) == "-" else str(path)
    text = _read_text(path, shown)
    first_line, _, body = text.lstrip("\n").partition("\n")
    if not first_line.strip():
        raise SignalError(f"{shown}: the file is empty (expected a header row such as t,x,y,z)")
    header = [name.strip() for name in next(csv.reader([first_line]))]
    _check_header(header, required, shown)
    if not body.strip():
        raise SignalError(f"{shown}: the file has a header but no samples")
    data = _parse_fast(body, len(header))
    if data is None:  # something is wrong: the careful scan finds where
        rows = list(csv.reader(io.StringIO(text)))
        while rows and not any(cell.strip() for cell in rows[-1]):
            rows.pop()
        data = _parse_rows(rows[1:], header, shown)
    times = data[:, header.index(TIME_COLUMN)]
    steps = np.diff(times)
    if np.any(steps <= 0):
        row = int(np.argmax(steps <= 0)) + 1
        raise SignalError(f"{shown}:{row + 2}: time must be strictly increasing (t = {times[row]:g} after {times[row - 1]:g})")
    columns = {name: data[:, index].copy() for index, name in enumerate(header) if name != TIME_COLUMN}
    return SignalTable(times.copy(), columns, shown)


def write_signal_csv(table: SignalTable, destination: str | Path | TextIO, digits: int = 12) -> None:
    """Write `table` as CSV (`t` first) to a path, "-" (standard output) or an open stream,
    with `digits` significant digits (17 reads back exactly)."""
    names = list(table.columns)
    data = np.column_stack([table.times] + [table.columns[name] for name in names])
    body = io.StringIO()
    body.write(",".join([TIME_COLUMN] + names) + "\n")
    np.savetxt(body, data, delimiter=",", fmt=f"%.{digits}g")
    if isinstance(destination, (str, Path)) and str(destination) != "-":
        write_atomically(Path(destination), body.getvalue())
    else:
        stream = sys.stdout if isinstance(destination, (str, Path)) else destination
        stream.write(body.getvalue())


def as_written(table: SignalTable, digits: int = 12) -> SignalTable:
    """`table` as `write_signal_csv` (with `digits`) and `read_signal_csv` give it back."""

    def rounded(values: np.ndarray) -> np.ndarray:
        return np.char.mod(f"%.{digits}g", np.asarray(values, dtype=float)).astype(float)

    return SignalTable(rounded(table.times), {name: rounded(values) for name, values in table.columns.items()}, source=table.source)


# --- Helper functions -----------------------------------------------------------------------


def _read_text(path: str | Path, shown: str) -> str:
    try:
        if str(path) == "-":
            return decoded(_read_stdin(), "CSV file")
        return read_text(path, "CSV file")
    except UnreadableFile as error:
        raise SignalError(f"{shown}: {error}") from None


def _read_stdin() -> bytes:
    data = sys.stdin.buffer.read(MAX_TEXT_BYTES + 1)
    if len(data) > MAX_TEXT_BYTES:
        raise UnreadableFile(f"the input is larger than {MAX_TEXT_BYTES // 1_000_000} MB; is it a CSV file?")
    return data


def _check_header(header: list[str], required: tuple[str, ...], shown: str) -> None:
    if any(not name for name in header):
        raise SignalError(f"{shown}:1: empty column name in the header")
    duplicates = sorted({name for name in header if header.count(name) > 1})
    if duplicates:
        raise SignalError(f"{shown}:1: duplicate column '{duplicates[0]}'")
    missing = [name for name in (TIME_COLUMN, *required) if name not in header]
    if missing:
        raise SignalError(f"{shown}:1: missing column '{missing[0]}' (the header has: {', '.join(header)})")


def _parse_fast(text: str, columns: int) -> np.ndarray | None:
    """The samples (`T x columns`) when every row is well formed and finite; None otherwise."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            data = np.loadtxt(io.StringIO(text), delimiter=",", ndmin=2, dtype=float)
        except ValueError:
            return None
    if data.shape[1] != columns or not np.all(np.isfinite(data)):
        return None
    return data


def _parse_rows(rows: list[list[str]], header: list[str], shown: str) -> np.ndarray:
    data = np.empty((len(rows), len(header)))
    for row_index, row in enumerate(rows):
        line = row_index + 2
        if len(row) != len(header):
            raise SignalError(f"{shown}:{line}: expected {len(header)} values, found {len(row)}")
        for column_index, cell in enumerate(row):
            try:
                value = float(cell)
            except ValueError:
                raise SignalError(f"{shown}:{line}: column '{header[column_index]}' has {cell.strip()!r}, not a number") from None
            if not math.isfinite(value):
                raise SignalError(f"{shown}:{line}: column '{header[column_index]}' is {cell.strip()}")
            data[row_index, column_index] = value
    return data
