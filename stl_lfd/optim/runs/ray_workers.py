"""Parallel trials on a Ray cluster (`optimize --ray`): the interface of `workers.WorkerPool`,
with Ray tasks in place of local processes.

Each trial is a Ray task of one CPU. The worker process that runs it builds the run's
objective (its PyBullet or MuJoCo world, or its executor command) at its first trial of the
run and keeps it for the next ones (Ray reuses its worker processes). A batch holds `workers`
trials, and the next batch is submitted as soon as it is proposed: it starts on the CPUs the
current one leaves free. A trial whose worker process or node
dies is run again by Ray on any node with a free CPU, up to `RETRIES` times; the driver
records each trial once, when its outcome arrives. Beyond that the run stops as with a dead
local worker, and `--resume` continues it.
"""

from __future__ import annotations

import logging
import os
import uuid
from typing import Any, Callable

import numpy as np

from stl_lfd.errors import ConfigError
from stl_lfd.optim.runs.workers import THREAD_VARIABLES, WORKER_NICENESS, died
from stl_lfd.optim.trials import Outcome, describe_error
from stl_lfd.spelling import spelled

RETRIES = 3  # times a trial whose worker process or node died is run again
_built: tuple[str, Any] | None = None  # in a Ray worker process: the run it last served (its key) and that run's objective


def connect(address: str | None) -> None:
    """Join a Ray cluster once per process: `auto` (the cluster this machine belongs to), a
    cluster's address, or None for a new local one; nothing when Ray is already initialised
    (by the caller, or an earlier run in this process)."""
    try:
        import ray
    except ImportError:
        raise ConfigError(f"{spelled('ray')} needs Ray: pip install 'stlopt[ray]'") from None
    if ray.is_initialized():
        return
    try:
        ray.init(address=address, runtime_env={"env_vars": {name: "1" for name in THREAD_VARIABLES}}, log_to_driver=False, logging_level=logging.WARNING)
    except ConnectionError as error:
        raise ConfigError(f"{spelled('ray')} {address}: {str(error).split('. ')[0]}") from None
    _messages_to_stderr()


def _messages_to_stderr() -> None:
    """Ray prints its nodes' messages (a worker died, a task is retried) on stdout, where a
    command's output is data (`optimize` prints the summary's JSON): onto stderr with them."""
    from ray._private import worker

    printed = getattr(worker, "print_to_stdstream", None)
    if printed is None or getattr(printed, "to_stderr", False):
        return

    def to_stderr(data: dict, ignore_prefix: bool) -> None:
        printed({**data, "is_err": True}, ignore_prefix)

    to_stderr.to_stderr = True  # type: ignore[attr-defined]
    worker.print_to_stdstream = to_stderr


def evaluate_trial(key: str, make_objective: Callable[[], Callable[[np.ndarray, int], Outcome]], x: np.ndarray, trial: int) -> Outcome | str:
    """In a Ray worker process: trial `trial` at `x` on the objective of the run `key` (built at
    the process's first trial of that run), or the message of its error."""
    try:  # a world that cannot be built (a scene file missing on this node) fails the trial, with why
        objective = _built[1] if _built is not None and _built[0] == key else _objective_for(key, make_objective)
        return objective(x, trial)
    except Exception as error:
        return describe_error(error)


def _objective_for(key: str, make_objective: Callable[[], Callable[[np.ndarray, int], Outcome]]) -> Callable[[np.ndarray, int], Outcome]:
    """Build the objective of the run `key` in this process, in place of the previous run's."""
    global _built
    import warnings

    if _built is None:  # the process's first run: as a local worker, the driver's proposal on the same node comes first
        os.nice(WORKER_NICENESS)
        warnings.simplefilter("ignore")  # a task has no terminal: tracking warnings would be lost
    else:
        close = getattr(_built[1], "close", None)
        if close is not None:
            close()
    objective = make_objective()
    _built = (key, objective)
    return objective


class RayPool:
    """Trials as Ray tasks, each on the objective `make_objective()` builds in the process that
    runs it (picklable), on the cluster at `address` (see `connect`). The trial loop hands it
    batches of `workers` trials; Ray runs as many at once as the cluster has free CPUs."""

    def __init__(self, make_objective: Callable[[], Callable[[np.ndarray, int], Outcome]], address: str | None) -> None:
        connect(address)
        import ray

        self.key = uuid.uuid4().hex
        self.factory = ray.put(make_objective)
        self.task = ray.remote(num_cpus=1, max_retries=RETRIES)(evaluate_trial)
        self.running: list[Any] = []

    def __call__(self, points: list[tuple[np.ndarray, int]]) -> Callable[[], list[Outcome | str]]:
        """Start evaluating each `(x, trial number)`; returns the function that waits for the
        outcomes (or error messages), in order."""
        import ray

        futures = [self.task.remote(self.key, self.factory, x, trial) for x, trial in points]
        self.running.extend(futures)

        def wait() -> list[Outcome | str]:
            try:
                outcomes = ray.get(futures)
            except ray.exceptions.RayError:  # a worker process or node died more than RETRIES times
                self.stop()
                raise died(points, f"a Ray worker died more than {RETRIES} times") from None
            except BaseException:  # Ctrl-C: the trials in flight are lost, as with one worker
                self.stop()
                raise
            self.running = [future for future in self.running if future not in futures]
            return outcomes

        return wait

    def stop(self) -> None:
        """Cancel the trials in flight (they are lost)."""
        import ray

        for future in self.running:
            ray.cancel(future, force=True)
        self.running = []

    def close(self) -> None:
        """Nothing runs any more; the worker processes keep their objective until the next run."""
        self.running = []
