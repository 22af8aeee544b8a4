"""Executors never outlive their supervisor: a watchdog process per execution, and a record of
the executor's process group in its exchange folder.

An executor command may drive a real robot, so when the process that started it dies, however
it dies (kill -9 included, in the main process or a worker), the executor must stop too. Each
execution gets a small watchdog process that holds the read end of a pipe whose write end only
the supervisor holds: the kernel closes it when the supervisor ends, and a watchdog that sees
the pipe close without the supervisor's `done` stops the executor's process group (SIGTERM,
then SIGKILL after the grace period). The executor's group is also recorded in the exchange
folder (`executor.json`) until the execution is over, so that a resumed run stops any executor
of the same trial still running before it starts another (never two at once for one trial).

An execution is over only once the executor's whole process group is gone: what it started and
left running is stopped with it, and (this process being their subreaper) reaped here.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable

GROUP_FILE = "executor.json"
PR_SET_CHILD_SUBREAPER = 36  # prctl's option, from <linux/prctl.h>
DONE = b"done"
# What the watchdog runs (standard library only, so that it starts in a few tens of ms).
WATCHDOG = """
import os, signal, sys, time
group, grace = int(sys.argv[1]), float(sys.argv[2])
if sys.stdin.buffer.read() != b"done":
    for number in (signal.SIGTERM, signal.SIGKILL):
        try:
            os.killpg(group, number)
        except (ProcessLookupError, PermissionError):
            break
        end = time.monotonic() + grace
        while number == signal.SIGTERM and time.monotonic() < end:
            time.sleep(0.05)
            try:
                os.killpg(group, 0)
            except (ProcessLookupError, PermissionError):
                break
"""


class Watchdog:
    """Stops process group `group` (SIGTERM, then SIGKILL after `grace` seconds) unless
    `release` is called first: when this process dies, its pipe closes without a word."""

    def __init__(self, group: int, grace: float) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-S", "-c", WATCHDOG, str(group), str(grace)],
            stdin=subprocess.PIPE, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True,
        )  # fmt: skip

    def release(self) -> None:
        """The execution is over and its group stopped by us: the watchdog goes without a shot."""
        try:
            self.process.stdin.write(DONE)
            self.process.stdin.close()
        except OSError:  # it died already
            pass
        self.process.wait()


def adopt_orphans() -> None:
    """Make this process the reaper of its descendants' orphans (Linux's child subreaper): what
    an executor leaves running when it exits is then this process's child, so that once its
    group is stopped `reap_group` collects it, instead of it staying a zombie until init does."""
    if sys.platform == "linux":
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0)


def reap_group(group: int, grace: float) -> None:
    """Collect the ended members of process group `group` that are this process's children,
    waiting at most `grace` seconds for the last of them."""
    deadline = time.monotonic() + grace
    while True:
        try:
            pid, _ = os.waitpid(-group, os.WNOHANG)
        except ChildProcessError:  # none left
            return
        if pid == 0:
            if time.monotonic() > deadline:
                return
            time.sleep(0.005)


def record_group(folder: Path, group: int) -> None:
    """Note in `folder` that the executor's process group `group` is running."""
    (folder / GROUP_FILE).write_text(json.dumps({"group": group, "started": _start_time(group)}) + "\n")


def forget_group(folder: Path) -> None:
    (folder / GROUP_FILE).unlink(missing_ok=True)


def stop_leftover(folder: Path, grace: float) -> bool:
    """Stop the executor a killed supervisor left running in `folder` (if the process recorded
    there is still that executor); whether there was one."""
    path = folder / GROUP_FILE
    try:
        data = json.loads(path.read_text())
        group, started = int(data["group"]), data["started"]
    except (OSError, ValueError, KeyError, TypeError):
        return False
    path.unlink(missing_ok=True)
    if started is None or _start_time(group) != started:  # gone, or its number reused by another process
        return False
    stop_group(group, grace, lambda: group_running(group))
    return True


def stop_group(group: int, grace: float, running: Callable[[], bool]) -> None:
    """SIGTERM to process group `group`, then, after `grace` seconds or as soon as `running()`
    says it has ended, SIGKILL to whatever is left of it."""
    if not _signal_group(group, signal.SIGTERM):
        return
    deadline = time.monotonic() + grace
    while running() and time.monotonic() < deadline:
        time.sleep(0.02)
    _signal_group(group, signal.SIGKILL)


def group_running(group: int) -> bool:
    """Whether a process of the group still runs; a zombie (ended, waiting for its parent or
    init to reap it) does not."""
    proc = Path("/proc")
    if not proc.is_dir():
        return _signal_group(group, 0)
    for entry in proc.iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except (OSError, IndexError):
                continue
            if int(fields[2]) == group and fields[0] != "Z":
                return True
    return False


def _signal_group(group: int, number: int) -> bool:
    """Send signal `number` to the process group; whether it still had a member."""
    try:
        os.killpg(group, number)
    except (ProcessLookupError, PermissionError):
        return False
    return True


def _start_time(pid: int) -> int | None:
    """When process `pid` started (clock ticks since boot), or None when it does not run."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except (OSError, IndexError):
        return None
    return None if fields[0] == "Z" else int(fields[19])
