"""Parallel trials: worker processes, each holding its own objective (and so its own PyBullet
world, or its own executor command) for the whole run.

Workers are spawned, not forked (forking after torch or pybullet started threads can
deadlock), run single-threaded, and are given the task and models once, at start-up. Each
batch of `(x, trial)` pairs is executed one pair per worker; the outcomes come back in the
batch's order, a failure as its message.
"""

from __future__ import annotations

import multiprocessing
import os
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from stl_lfd.hsmm import HSMM
from stl_lfd.optim.loop import Outcome, describe_error
from stl_lfd.optim.task import Task

_objective = None  # the worker process's own objective, built by `_start`


class WorkerPool:
    """`workers` processes that evaluate trials of `task` (see the module docstring)."""

    def __init__(self, task: Task, models: dict[str, HSMM], run_dir: Path | None, workers: int) -> None:
        context = multiprocessing.get_context("spawn")
        self.pool = ProcessPoolExecutor(max_workers=workers, mp_context=context, initializer=_start, initargs=(task, models, run_dir))

    def __call__(self, points: list[tuple[np.ndarray, int]]) -> list[Outcome | str]:
        """The outcome (or error message) of each `(x, trial number)`, in order."""
        futures = [self.pool.submit(_evaluate, x, trial) for x, trial in points]
        try:
            return [future.result() for future in futures]
        except BaseException:  # Ctrl-C: the trials in flight are lost, as with one worker
            self.stop()
            raise

    def stop(self) -> None:
        """End the workers now (SIGTERM: each stops its executor command, if any, first)."""
        for process in multiprocessing.active_children():
            process.terminate()
        self.pool.shutdown(wait=False, cancel_futures=True)

    def close(self) -> None:
        self.pool.shutdown(wait=True, cancel_futures=True)


def _start(task: Task, models: dict[str, HSMM], run_dir: Path | None) -> None:
    global _objective
    for name in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        os.environ[name] = "1"
    import signal
    import warnings

    from stl_lfd.optim.run import objective_for

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the main process's to handle
    signal.signal(signal.SIGTERM, _terminated)
    warnings.simplefilter("ignore")  # a worker has no terminal: tracking warnings would be lost
    _, _objective = objective_for(task, models)
    if run_dir is not None:
        _objective.exchange_in(run_dir)


def _terminated(number: int, frame: object) -> None:
    raise KeyboardInterrupt  # unwinds through the command backend, which stops its command


def _evaluate(x: np.ndarray, trial: int) -> Outcome | str:
    try:
        return _objective(x, trial)
    except Exception as error:
        return describe_error(error)
