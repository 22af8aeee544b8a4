"""`RunLock`: one writer per run directory."""

from __future__ import annotations

import fcntl
import os
from pathlib import Path
from typing import Any

from stl_lfd.errors import BusyError, RunError

LOCK_FILE = ".lock"


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
            raise BusyError(f"{shown}: the run is being written by another stlopt process (PID {holder}); wait for it to end or stop it") from None
        stream.seek(0)
        stream.truncate()
        stream.write(f"{os.getpid()}\n")
        stream.flush()
        return cls(stream)

    def release(self) -> None:
        if not self.stream.closed:
            fcntl.flock(self.stream.fileno(), fcntl.LOCK_UN)
            self.stream.close()
