"""Parallel trials on a Ray cluster (`optimize --ray`): the interface of `workers.WorkerPool`,
with Ray actors in place of local processes.

Each worker is an actor of one CPU that builds its objective (its PyBullet or MuJoCo world, or
its executor command) once and keeps it for its life. A batch gives each actor one trial in
turn. An actor whose process or node dies is started again (its objective built anew, on any
node with a free CPU) and its trial re-run there, up to `RESTARTS` times per actor; the driver
records each trial once, when its outcome arrives. Beyond that the run stops as with a dead
local worker, and `--resume` continues it.
"""

from __future__ import annotations

import logging
import os
from typing import Any, Callable

import numpy as np

from stl_lfd.errors import ConfigError, RunError
from stl_lfd.optim.runs.workers import THREAD_VARIABLES, WORKER_NICENESS, died
from stl_lfd.optim.trials import Outcome, describe_error
from stl_lfd.spelling import spelled

RESTARTS = 3  # times an actor whose process or node died is started again, its trial re-run


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


class TrialWorker:
    """The body of one actor: an objective built once, evaluating trials one at a time."""

    def __init__(self, make_objective: Callable[[], Callable[[np.ndarray, int], Outcome]]) -> None:
        import warnings

        os.nice(WORKER_NICENESS)  # as a local worker: the driver's proposal on the same node comes first
        warnings.simplefilter("ignore")  # an actor has no terminal: tracking warnings would be lost
        self.objective = make_objective()

    def ready(self) -> bool:
        return True

    def pid(self) -> int:
        return os.getpid()

    def evaluate(self, x: np.ndarray, trial: int) -> Outcome | str:
        try:
            return self.objective(x, trial)
        except Exception as error:
            return describe_error(error)

    def close(self) -> None:
        close = getattr(self.objective, "close", None)
        if close is not None:
            close()


class RayPool:
    """`workers` Ray actors that evaluate trials, each with the objective `make_objective()`
    builds in it (picklable), on the cluster at `address` (see `connect`)."""

    def __init__(self, make_objective: Callable[[], Callable[[np.ndarray, int], Outcome]], workers: int, address: str | None) -> None:
        connect(address)
        import ray

        actor = ray.remote(num_cpus=1, max_restarts=RESTARTS, max_task_retries=RESTARTS)(TrialWorker)
        self.actors: list[Any] = [actor.remote(make_objective) for _ in range(workers)]
        self.turn = 0  # the actor that takes the next trial
        try:
            ray.get([worker.ready.remote() for worker in self.actors])  # every world built now
        except ray.exceptions.RayActorError as error:
            self.stop()
            raise RunError(f"a Ray worker could not start: {_cause(error)}") from None
        except BaseException:
            self.stop()
            raise

    def __call__(self, points: list[tuple[np.ndarray, int]]) -> Callable[[], list[Outcome | str]]:
        """Start evaluating each `(x, trial number)`; returns the function that waits for the
        outcomes (or error messages), in order."""
        import ray

        futures = []
        for x, trial in points:
            futures.append(self.actors[self.turn].evaluate.remote(x, trial))
            self.turn = (self.turn + 1) % len(self.actors)

        def wait() -> list[Outcome | str]:
            try:
                return ray.get(futures)
            except ray.exceptions.RayActorError:
                self.stop()
                raise died(points, f"a Ray worker died more than {RESTARTS} times") from None
            except BaseException:  # Ctrl-C: the trials in flight are lost, as with one worker
                self.stop()
                raise

        return wait

    def stop(self) -> None:
        """End the actors now (their trials in flight are lost)."""
        import ray

        for worker in self.actors:
            ray.kill(worker, no_restart=True)

    def close(self) -> None:
        """Close each actor's objective (its executor, its world), then end the actors."""
        import ray

        try:
            ray.get([worker.close.remote() for worker in self.actors])
        finally:
            self.stop()


def _cause(error: Exception) -> str:
    """The first line of what ended an actor, without Ray's wrapping."""
    cause = getattr(error, "cause", None) or error
    return str(cause).strip().splitlines()[-1] if str(cause).strip() else type(cause).__name__
