"""Parallel trials: worker processes, each holding its own objective (and so its own PyBullet
world, or its own executor command) for the whole run.

Workers are spawned, not forked (forking after torch or pybullet started threads can
deadlock), run single-threaded, and are given the task and models once, at start-up (an
`ObjectiveFactory`, which builds the objective in the worker from the task as read here). Each
batch of `(x, trial)` pairs is executed one pair per worker; the outcomes come back in the
batch's order, a failure as its message.

An outcome comes back through a file in a scratch folder, and only its name through the pool's
result pipe: a worker killed while writing a large outcome into that pipe would leave a partial
message there, and the pool waiting for its end forever; a name is written in one piece.

A worker that dies (killed, or crashed in native code) stops the run with one error line; the
trials in flight are lost, as with Ctrl-C, and `--resume` continues exactly. Workers watch
their parent and end themselves when it is gone (killed with SIGKILL, say), stopping their
executor commands first.
"""

from __future__ import annotations

import multiprocessing
import os
import pickle
import shutil
import tempfile
import threading
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from stl_lfd.errors import RunError
from stl_lfd.hsmm import HSMM
from stl_lfd.optim.inputs import TaskInputs
from stl_lfd.optim.objective import SkillObjective, objective_for
from stl_lfd.optim.trials import Outcome, describe_error
from stl_lfd.spelling import spelled

_objective = None  # the worker process's own objective, built by `_start`
_outbox: Path | None = None  # where the worker process writes its outcomes (`_handed_back`)
_busy = False  # whether the worker is evaluating a trial (a stop then unwinds it first)
THREAD_VARIABLES = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS")  # one thread per worker
WORKER_NICENESS = 10
PARENT_CHECK_SECONDS = 1.0  # how often a worker checks that the process that started it lives
ERROR_MARK = "error: "  # an outcome handed back as its error message, not as a file (`_evaluate`)


class WorkerPool:
    """`workers` processes that evaluate trials, each with the objective `make_objective()`
    builds in it (picklable; see the module docstring)."""

    def __init__(self, make_objective: Callable[[], Callable[[np.ndarray, int], Outcome]], workers: int) -> None:
        context = multiprocessing.get_context("spawn")
        saved = {name: os.environ.get(name) for name in THREAD_VARIABLES}
        os.environ.update({name: "1" for name in THREAD_VARIABLES})  # inherited by the workers as they start
        self.outbox = Path(tempfile.mkdtemp(prefix="stlopt-outcomes-"))
        try:
            self.pool = ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=_start, initargs=(make_objective, self.outbox))
            for future in [self.pool.submit(_ready) for _ in range(workers)]:  # start every worker (and its world) now
                future.result()
        except BaseException:
            self.stop()
            raise
        finally:
            for name, value in saved.items():
                os.environ.pop(name) if value is None else os.environ.__setitem__(name, value)

    def __call__(self, points: list[tuple[np.ndarray, int]]) -> Callable[[], list[Outcome | str]]:
        """Start evaluating each `(x, trial number)`; returns the function that waits for the
        outcomes (or error messages), in order."""
        try:
            futures = [self.pool.submit(_evaluate, x, trial) for x, trial in points]
        except BrokenProcessPool:  # a worker died on a trial submitted before these
            self.stop()
            raise died([]) from None

        def wait() -> list[Outcome | str]:
            try:
                return [self.taken_back(future.result()) for future in futures]
            except BrokenProcessPool:
                self.stop()
                raise died(points) from None
            except BaseException:  # Ctrl-C: the trials in flight are lost, as with one worker
                self.stop()
                raise

        return wait

    def taken_back(self, name: str) -> Outcome | str:
        """The outcome a worker handed back in the file `name` (`_handed_back`), read once, or
        the error message `_evaluate` sent instead."""
        if name.startswith(ERROR_MARK):
            return name[len(ERROR_MARK) :]
        path = self.outbox / name
        try:
            return pickle.loads(path.read_bytes())
        finally:
            path.unlink(missing_ok=True)

    def stop(self) -> None:
        """End the workers now (SIGTERM: each stops its executor command, if any, first)."""
        stop_children()
        self.close()

    def close(self) -> None:
        if hasattr(self, "pool"):
            self.pool.shutdown(wait=True, cancel_futures=True)
        shutil.rmtree(self.outbox, ignore_errors=True)


def died(points: list[tuple[np.ndarray, int]], what: str = "a worker process died (killed, or crashed)") -> RunError:
    """The error that stops a run whose worker died running the trials `points`."""
    numbers = [trial for _, trial in points]
    trials = "the trials in flight" if not numbers else f"trial {numbers[0]}" if len(numbers) == 1 else f"trials {numbers[0]} to {numbers[-1]}"
    return RunError(f"{what} while running {trials}; those trials are lost and the run stops here: continue it with the same command and {spelled('resume')}")


def _start(make_objective: Callable[[], Callable[[np.ndarray, int], Outcome]], outbox: Path) -> None:
    global _objective, _outbox
    import warnings

    stop_on_sigterm()
    watch_parent()
    # The next batch's proposal (in the main process) runs beside the batch's rollouts and is the
    # longer of the two: the rollouts yield the CPU to it, so that it never waits behind them.
    os.nice(WORKER_NICENESS)
    warnings.simplefilter("ignore")  # a worker has no terminal: tracking warnings would be lost
    _objective = make_objective()
    _outbox = outbox


def _ready() -> bool:
    return _objective is not None


def _evaluate(x: np.ndarray, trial: int) -> str:
    """In a worker: the name of the file holding the outcome of trial `trial` at `x`, or the
    message of its error."""
    try:
        outcome = run_stoppable(_objective, x, trial)
    except Exception as error:
        outcome = describe_error(error)
    try:
        return _handed_back(outcome, trial)
    except Exception as error:  # a full disk, say: the trial fails with why (short: through the pipe), the run goes on
        return f"{ERROR_MARK}its outcome could not be handed back ({describe_error(error)})"


def _handed_back(outcome: Outcome | str, trial: int) -> str:
    """The name of the file in the outbox that holds `outcome`."""
    assert _outbox is not None
    path = _outbox / f"trial-{trial}.pickle"
    partial = path.with_suffix(".partial")
    partial.write_bytes(pickle.dumps(outcome, protocol=pickle.HIGHEST_PROTOCOL))
    partial.replace(path)
    return path.name


def stop_on_sigterm() -> None:
    """In a worker process: ignore Ctrl-C (the main process's to handle) and make SIGTERM stop
    the work in progress through its clean-up (`run_stoppable`), or end an idle worker."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _terminated)


def watch_parent(period: float = PARENT_CHECK_SECONDS) -> None:
    """In a worker process: end it (through SIGTERM, so that its work unwinds) once the process
    that started it is gone, which no signal tells a child when the parent is SIGKILLed."""
    import signal

    parent = os.getppid()

    def watch() -> None:
        while os.getppid() == parent:
            threading.Event().wait(period)
        os.kill(os.getpid(), signal.SIGTERM)

    threading.Thread(target=watch, name="parent-watch", daemon=True).start()


def run_stoppable(function: Callable[..., Any], *args: Any) -> Any:
    """`function(*args)` in a worker that `stop_on_sigterm` set up: stopped, it unwinds (an
    executor command is stopped, a scratch folder removed) and the worker exits, instead of the
    pool catching the interrupt and waiting for more work."""
    global _busy
    _busy = True
    try:
        return function(*args)
    except KeyboardInterrupt:
        os._exit(130)
    finally:
        _busy = False


def _terminated(number: int, frame: object) -> None:
    if _busy:
        raise KeyboardInterrupt
    os._exit(128 + number)


def stop_children(grace: float = 5.0) -> None:
    """SIGTERM to every child process of this one, SIGKILL to those still running after `grace` s."""
    children = multiprocessing.active_children()
    for process in children:
        process.terminate()
    for process in children:
        process.join(grace)
        if process.is_alive():
            process.kill()
            process.join()


@dataclass(frozen=True)
class ObjectiveFactory:
    """Makes the objective of a task in another process (a parallel worker): picklable, so
    that the worker builds its own world, or its own executor command, once at start-up, from
    the task's `inputs` as read here. `run_dir`: where the command backend's exchange folders go
    (None: a scratch folder)."""

    inputs: TaskInputs
    models: dict[str, HSMM]
    run_dir: Path | None = None

    def __call__(self) -> SkillObjective:
        _, objective = objective_for(self.inputs, self.models)
        if self.run_dir is not None:
            objective.exchange_in(self.run_dir)
        return objective
