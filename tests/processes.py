"""Helpers of the tests that run stlopt in a child process and stop it as Ctrl-C would."""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path
from typing import Callable

import pytest


def wait_for(condition: Callable[[], bool], timeout: float = 120.0) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if time.monotonic() > deadline:
            pytest.fail("timed out waiting")
        time.sleep(0.05)


def deliverable_sigint() -> None:
    """In the child: SIGINT handled and unblocked as in a terminal. A shell that ran the tests in
    the background leaves it ignored, and a test worker's thread may have it blocked; children
    inherit both."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT})


def interrupt(process: subprocess.Popen) -> tuple[str, str]:
    """Send SIGINT until `process` ends; its stdout and stderr. Python can lose a SIGINT that
    lands while a finaliser (`__del__`) runs, as a second Ctrl-C in a terminal would make up for."""
    for _ in range(10):
        process.send_signal(signal.SIGINT)
        try:
            return process.communicate(timeout=5)
        except subprocess.TimeoutExpired:
            continue
    status = Path(f"/proc/{process.pid}/status")
    if process.poll() is not None or not status.exists():
        pytest.fail("the process ended, but something it started kept its output open")
    masks = [line for line in status.read_text().splitlines() if line.startswith(("SigBlk", "SigIgn", "SigCgt"))]
    process.kill()
    pytest.fail(f"the process went on through 10 SIGINTs ({'; '.join(masks)})")


def worker_processes(parent: int) -> list[int]:
    """The multiprocessing workers `parent` spawned (not its resource tracker)."""
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
            command = (entry / "cmdline").read_bytes().replace(b"\0", b" ")
        except OSError:
            continue
        if int(stat.rsplit(")", 1)[1].split()[1]) == parent and b"spawn_main" in command:
            found.append(int(entry.name))
    return found


def alive(pid: int) -> bool:
    """Whether `pid` runs (a zombie does not)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False
