"""The `command` backend: each execution is run by an external program, such as the user's
controller stack on a real robot.

For every execution, stlopt checks the reference against the scene's safety limits, writes it
as a reference CSV into an exchange folder and runs the command, which must execute it and
write the recorded signals as a signal CSV. In the run directory the exchange folders are
`executions/initial/` (the unoptimised skill) and `executions/trial-NNNN/`, each holding
`reference.csv`, `signals.csv` (written by the command), `stdout.txt` and `stderr.txt`.

Placeholders in the command's arguments: `{reference}`, `{signals}` (the two paths), `{trial}`
(0 for the unoptimised skill), `{run_dir}`, `{scene}` (built-in name or path) and `{rate}`
(samples/s to record). The same values are in the environment as `STLOPT_REFERENCE`,
`STLOPT_SIGNALS`, `STLOPT_TRIAL`, `STLOPT_RUN_DIR`, `STLOPT_SCENE` and `STLOPT_RATE`.

The command runs without a shell (an argument list; a string is split as a shell would) unless
`shell` is set, in its own process group, so that a timeout or Ctrl-C stops it with everything
it started; what it leaves running when it exits is stopped too, after every execution. It never
outlives the process that started it: a watchdog stops it when that process dies, even by
kill -9 (`watchdog.py`).
"""

from __future__ import annotations

import hashlib
import os
import shutil
import signal
import subprocess
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Iterator

import numpy as np

from stl_lfd.errors import ExecutionError
from stl_lfd.signals import SignalTable, read_signal_csv
from stl_lfd.sim.backend import BackendBase, BackendOptions, Capabilities
from stl_lfd.sim.executor import Command
from stl_lfd.sim.plausibility import check_recorded
from stl_lfd.sim.reference import Reference, Rollout, write_reference_csv
from stl_lfd.sim.safety import check_reference
from stl_lfd.sim.scene import Scene
from stl_lfd.sim.watchdog import Watchdog, adopt_orphans, forget_group, group_running, reap_group, record_group, stop_group, stop_leftover

STOP_GRACE = 3.0  # seconds between SIGTERM and SIGKILL when a command is stopped
EXECUTIONS_DIR = "executions"
REFERENCE_FILE, SIGNALS_FILE = "reference.csv", "signals.csv"  # in a trial's exchange folder


def exchange_folder(run_dir: Path, trial: int) -> Path:
    """Where the files of trial `trial` (0: the unoptimised skill) are exchanged."""
    return Path(run_dir) / EXECUTIONS_DIR / ("initial" if trial == 0 else f"trial-{trial:04d}")


def reference_path(run_dir: Path, trial: int) -> Path:
    """The reference of trial `trial` as handed to its executor (`stlopt ask`, or the command)."""
    return exchange_folder(run_dir, trial) / REFERENCE_FILE


class CommandBackend(BackendBase):
    """Executes references by running a `Command`.

    Attributes:
        folder: the run directory the exchange folders go in; None for a temporary folder,
            removed after the execution.
        trial: the trial number of the next execution (0: the unoptimised skill).
    """

    name = "command"
    capabilities = Capabilities(measures_force=True, needs_command=True)

    def __init__(self, command: Command, folder: Path | None = None) -> None:
        self.command = command
        self.folder = folder
        self.trial = 0

    @classmethod
    def open(cls, options: BackendOptions) -> "CommandBackend":
        assert options.command is not None  # new_backend checks it
        return cls(options.command, options.folder)

    def file_executions(self, folder: Path | None = None, trial: int | None = None) -> None:
        """Exchange folders go under `folder` (the run directory), named by `trial`."""
        if folder is not None:
            self.folder = Path(folder)
        if trial is not None:
            self.trial = trial

    def run(self, reference: Reference, scene: Scene, rate: float, observer: Callable | None = None) -> Rollout:
        """Check `reference`, hand it to the command, and return the signals it recorded."""
        gate(reference, scene)
        with self._exchange() as folder:
            reference_path, signals_path = folder / REFERENCE_FILE, folder / SIGNALS_FILE
            write_reference_csv(reference, reference_path, scene.gripper_opening)
            written = _digest(reference_path)
            signals_path.unlink(missing_ok=True)  # left by an execution that was interrupted
            values = {
                "reference": str(reference_path.resolve()), "signals": str(signals_path.resolve()), "trial": str(self.trial),
                "run_dir": str(Path(self.folder).resolve()) if self.folder is not None else str(folder.resolve()),
                "scene": scene.source or scene.name, "rate": f"{rate:g}",
            }  # fmt: skip
            run_command(self.command, values, folder, kept=self.folder is not None)
            if not reference_path.is_file() or _digest(reference_path) != written:
                raise ExecutionError(f"{reference_path}: the command removed or changed the reference it was given")
            if not signals_path.is_file():
                raise ExecutionError(f"the command exited without writing {signals_path}{_last_words(folder, self.folder is not None)}")
            signals = read_signal_csv(signals_path, required=("x", "y", "z"))
            check_recorded(signals, reference, scene, rate)
        return Rollout(signals, tracking_error(signals, reference))

    @contextmanager
    def _exchange(self) -> Iterator[Path]:
        if self.folder is not None:
            folder = exchange_folder(self.folder, self.trial)
            folder.mkdir(parents=True, exist_ok=True)
            yield folder
            return
        folder = Path(tempfile.mkdtemp(prefix="stlopt-execution-"))
        try:
            yield folder
        finally:
            shutil.rmtree(folder, ignore_errors=True)


def gate(reference: Reference, scene: Scene) -> None:
    """The safety gate every reference passes before it leaves stlopt: the scene's limits.

    Raises:
        UnsafeReference: outside the workspace or too fast (see `check_reference`).
        ExecutionError: the scene declares no limits.
    """
    if scene.safety is None:
        raise ExecutionError(f"the scene {scene.name} declares no 'safety' (workspace and max_speed), which references need before they leave stlopt")
    check_reference(reference, scene.safety)


def run_command(command: Command, values: dict[str, str], folder: Path, kept: bool = True) -> None:
    """Run `command` with `values` for its placeholders (and in its environment), its output in
    `folder/stdout.txt` and `folder/stderr.txt`; its process group is stopped (and reaped) before
    this returns, whether it exited, timed out or was interrupted by Ctrl-C.
    Errors name `folder/stderr.txt` only when the folder is `kept` (not a temporary one).

    Raises:
        ExecutionError: the command cannot start, fails, is killed or times out.
    """
    environment = dict(os.environ, **{f"STLOPT_{name.upper()}": value for name, value in values.items()})
    stop_leftover(folder, STOP_GRACE)  # a killed run's executor of this very trial: never two at once
    adopt_orphans()
    with open(folder / "stdout.txt", "wb") as stdout, open(folder / "stderr.txt", "wb") as stderr:
        try:
            process = subprocess.Popen(
                command.arguments(values), shell=command.shell, cwd=command.cwd, env=environment,
                stdin=subprocess.DEVNULL, stdout=stdout, stderr=stderr, start_new_session=True,
            )  # fmt: skip
        except OSError as error:
            raise ExecutionError(
                f"cannot start the command {command.run[0].split()[0] if command.shell else command.run[0]!r} ({error.strerror or error})"
            ) from None
        watchdog = None
        try:
            record_group(folder, process.pid)
            watchdog = Watchdog(process.pid, STOP_GRACE)  # stops the command if this process dies
            status = process.wait(timeout=command.timeout)
        except subprocess.TimeoutExpired:
            stop_process_group(process)
            raise ExecutionError(f"the command did not finish within its timeout of {command.timeout:g} s and was stopped{_last_words(folder, kept)}") from None
        except BaseException:  # Ctrl-C: nothing the command started may outlive us
            stop_process_group(process)
            raise
        else:
            stop_process_group(process)  # what it started and left behind ends with the execution
        finally:
            if watchdog is not None:
                watchdog.release()
            forget_group(folder)
    if status < 0:
        raise ExecutionError(f"the command was killed by {signal.Signals(-status).name}{_last_words(folder, kept)}")
    if status != 0:
        raise ExecutionError(f"the command exited with status {status}{_last_words(folder, kept)}")


def stop_process_group(process: subprocess.Popen) -> None:
    """SIGTERM to the process's group (the command and everything it started), SIGKILL to what
    is left once they have all ended or after `STOP_GRACE` seconds."""
    stop_group(process.pid, STOP_GRACE, lambda: process.poll() is None or group_running(process.pid))
    process.wait()
    reap_group(process.pid, STOP_GRACE)


def tracking_error(signals: SignalTable, reference: Reference) -> np.ndarray:
    """Distance (m) between the recorded positions and the reference at the recorded times."""
    recorded = np.column_stack([signals.columns[axis] for axis in ("x", "y", "z")])
    return np.linalg.norm(recorded - reference.positions_at(signals.times), axis=1)


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _last_words(folder: Path, kept: bool = True) -> str:
    """`: <the last line of its stderr> (see folder/stderr.txt)`, or that it wrote nothing; the
    file is named only when the folder is `kept`."""
    path = folder / "stderr.txt"
    try:
        lines = [line.strip() for line in path.read_text(errors="replace").splitlines() if line.strip()]
    except OSError:
        return ""
    if not kept:
        return f": {lines[-1][:300]}" if lines else " (nothing on stderr)"
    return f": {lines[-1][:300]} (see {path})" if lines else f" (nothing on stderr: {path})"
