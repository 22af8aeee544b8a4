"""`trials.jsonl` read as it grows: the one reader of a run's trial lines.

The optimiser appends one JSON line per finished trial. `TrialLog.read_new` returns the
complete lines written since its last call, a chunk at a time (never the whole file at
once), and keeps the bytes of a line still being written as `tail`. `RunDirectory.trials`
reads the log once and checks every trial; the dashboard keeps a `TrialLog` per run and reads
only what was appended since its last refresh.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator

import orjson

from stl_lfd.files import open_regular

CHUNK_BYTES = 4_000_000


class LongLine(ValueError):
    """A line of the log longer than the reader's limit (a file that is not a trial log)."""


@dataclass(frozen=True)
class LogLine:
    """A complete line of the log: its number in the file (1 for the first) and its JSON,
    None when the line is not JSON."""

    number: int
    record: Any


class TrialLog:
    """The trial lines of one `trials.jsonl`, read from where the last read stopped.

    Attributes:
        offset: bytes of the file consumed (complete lines only).
        lines: complete lines consumed, blank ones included (line numbers count them).
        tail: the bytes after the last newline at the last read: a line being written, or
            cut short by a kill.
    """

    def __init__(self, path: Path, max_line_bytes: int | None = None) -> None:
        self.path = Path(path)
        self.max_line_bytes = max_line_bytes
        self.offset = 0
        self.lines = 0
        self.tail = b""

    def read_new(self) -> Iterator[LogLine]:
        """The non-blank complete lines appended since the last read, in order. A line counts
        as consumed once the caller asks for the next one, so a caller that stops at a bad
        line meets it again at the next read.

        Raises:
            FileNotFoundError, IsADirectoryError, UnreadableFile (not a regular file), OSError;
            LongLine for a line over `max_line_bytes`.
        """
        with open_regular(self.path, "trials.jsonl") as stream:
            stream.seek(self.offset)
            self.tail = b""
            while chunk := stream.read(CHUNK_BYTES):
                data = self.tail + chunk
                cut = data.rfind(b"\n") + 1
                self.tail = data[cut:]
                yield from self._lines(data[:cut])
                self._check_length(len(self.tail), self.lines + 1)

    def _lines(self, data: bytes) -> Iterator[LogLine]:
        for line in data.split(b"\n")[:-1]:  # data ends with a newline; offsets count exactly the bytes read
            self._check_length(len(line), self.lines + 1)
            if line.strip():
                yield LogLine(self.lines + 1, decoded(line))
            self.lines += 1
            self.offset += len(line) + 1

    def _check_length(self, length: int, number: int) -> None:
        if self.max_line_bytes is not None and length > self.max_line_bytes:
            raise LongLine(f"line {number}: longer than {self.max_line_bytes // 1_000_000} MB, not a trial record")


def decoded(line: bytes) -> Any:
    """A line of JSON, None when it is not: orjson first (3x faster), the standard library for
    what only it reads (the NaN and Infinity that Python writes for such floats)."""
    try:
        return orjson.loads(line)
    except orjson.JSONDecodeError:
        pass
    try:
        return json.loads(line)
    except (ValueError, RecursionError):
        return None
