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
import re
import socket
import sys
import tempfile
import threading
import time
import uuid
from contextlib import contextmanager
from typing import Any, Callable, Iterator

import numpy as np

from stl_lfd.errors import ConfigError, RunError
from stl_lfd.optim.runs.workers import THREAD_VARIABLES, WORKER_NICENESS, died
from stl_lfd.optim.trials import Outcome, describe_error
from stl_lfd.spelling import spelled

RETRIES = 3  # times a trial whose worker process or node died is run again
CONNECT_SECONDS = 5.0  # an address that accepts no connection within this is refused
HEAD_PATIENCE = 5.0  # seconds a joined cluster's head may not answer before the run stops
_built: tuple[str, Any] | None = None  # in a Ray worker process: the run it last served (its key) and that run's objective


def connect(address: str | None, watch: bool = False) -> None:
    """Join a Ray cluster once per process: `auto` (the cluster this machine belongs to), a
    cluster's address, or None for a new local one; nothing when Ray is already initialised
    (by the caller, or an earlier run in this process). An address is checked first (its form,
    and that something answers there within `CONNECT_SECONDS`), and every failure to join is
    one ConfigError line. With `watch` (the command line's runs), a head that stops answering
    then ends the process with one line (`watch_head`)."""
    try:
        import ray
    except ImportError:
        raise ConfigError(f"{spelled('ray')} needs Ray: pip install 'stlopt[ray]'") from None
    if ray.is_initialized():
        return
    if address not in (None, "auto"):
        check_answers(address)
    with captured_stderr() as printed:  # Ray's core prints a line a second while it retries
        try:
            ray.init(address=address, runtime_env={"env_vars": {name: "1" for name in THREAD_VARIABLES}}, log_to_driver=False, logging_level=logging.WARNING)
        except Exception as error:  # ConnectionError, RuntimeError, ValueError: whatever Ray raises, one line
            problem = join_problem(error, printed())
        else:
            problem = ""
    if problem:
        raise ConfigError(f"{spelled('ray')} {address}: {problem}")
    _messages_to_stderr()
    if watch and address is not None:
        watch_head(address)


def check_answers(address: str) -> None:
    """ConfigError unless `address` is `HOST:PORT` (or `ray://HOST:PORT`) and something accepts
    a connection there within `CONNECT_SECONDS` (Ray itself would wait for minutes)."""
    host, port = split_address(address)
    error = _unanswered(host, port, CONNECT_SECONDS)
    if error is not None:
        reason = "no answer" if isinstance(error, TimeoutError) else (error.strerror or str(error))
        raise ConfigError(
            f"{spelled('ray')} {address}: nothing answers there ({reason}); start the cluster's head ('ray start' on the head node) "
            "and give the address it prints, or 'auto' on one of its nodes"
        ) from None


def split_address(address: str) -> tuple[str, int]:
    """`(host, port)` of `HOST:PORT`, `[IPv6]:PORT` or `ray://HOST:PORT`; ConfigError otherwise."""
    usage = f"{spelled('ray')} {address!r}: not a cluster address (HOST:PORT, as 'ray start' prints it on the head node, or 'auto')"
    host, colon, port = address.removeprefix("ray://").rpartition(":")
    host = host.removeprefix("[").removesuffix("]")
    if not colon or not port.isdigit() or not 0 < int(port) < 65536 or not re.fullmatch(r"[A-Za-z0-9.:_-]+", host or "-"):
        raise ConfigError(usage)
    return host, int(port)


@contextmanager
def captured_stderr() -> Iterator[Callable[[], str]]:
    """Send what this process (Ray's C++ core included) writes on stderr to a temporary file
    while the block runs; yields the function that reads what was written (inside the block)."""
    sys.stderr.flush()
    saved = os.dup(2)
    with tempfile.TemporaryFile() as capture:
        os.dup2(capture.fileno(), 2)
        try:
            yield lambda: _read_from_start(capture)
        finally:
            sys.stderr.flush()
            os.dup2(saved, 2)
            os.close(saved)


def _read_from_start(stream: Any) -> str:
    stream.seek(0)
    return stream.read(1_000_000).decode(errors="replace")


def join_problem(error: Exception, printed: str = "") -> str:
    """What a failure to join a cluster says, in one line (`printed`: what Ray printed while it
    tried); Ray's token authentication named when it is the cause."""
    text = " ".join(str(error).split())
    if "nauthenticated" in text + printed or "InvalidAuthToken" in printed or "auth token" in text.lower():
        return (
            "the cluster refused this process (it uses Ray's token authentication): set RAY_AUTH_MODE=token and its token "
            "in RAY_AUTH_TOKEN or RAY_AUTH_TOKEN_PATH, as on the cluster's nodes ('ray get-auth-token' prints it there)"
        )
    return text.split(". ")[0][:300] or type(error).__name__


def watch_head(address: str, every: float = 1.0, patience: float = HEAD_PATIENCE) -> threading.Thread:
    """A daemon thread that checks, every `every` seconds, that the cluster's head (its GCS)
    accepts connections; after `patience` seconds without, it ends the process with one line
    and the resume hint, before Ray's own 60 s wait ends it without a word. The trials
    recorded so far are on disk (each line is synced when written)."""
    gcs = _gcs_address() or address
    try:
        host, port = split_address(gcs)
    except ConfigError:
        host, port = None, 0

    message = (  # spelled here: options are spelled as the command line's in its thread only
        f"error: {spelled('ray')} {address}: the cluster's head stopped answering; the recorded trials are kept: "
        f"continue the run with the same command and {spelled('resume')}\n"
    )

    def watch() -> None:
        silent_since = None
        while host is not None:
            time.sleep(every)
            if _unanswered(host, port, every) is None:
                silent_since = None
                continue
            silent_since = silent_since or time.monotonic()
            if time.monotonic() - silent_since >= patience:
                sys.stderr.write(message)
                sys.stderr.flush()
                os._exit(RunError.exit_code)

    thread = threading.Thread(target=watch, name="ray-head-watch", daemon=True)
    thread.start()
    return thread


def _unanswered(host: str, port: int, timeout: float) -> OSError | None:
    """Why nothing accepted a connection at `host:port` within `timeout` s, None when something did."""
    try:
        socket.create_connection((host, port), timeout=timeout).close()
    except OSError as error:
        return error
    return None


def _gcs_address() -> str | None:
    """The address of the joined cluster's GCS (its head), as Ray knows it."""
    try:
        import ray

        address = ray.get_runtime_context().gcs_address if ray.is_initialized() else None
    except Exception:  # an older Ray without it: the address given is watched
        return None
    return str(address) if address else None


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
