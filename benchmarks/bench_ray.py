"""Trials on Ray against trials in this process: phi1 on PyBullet, the same seed, run with one
worker in this process, then with one and with two Ray actors on a local Ray of two CPUs (and
two local worker processes for comparison). The table shows the wall time per trial, the
speed-up of two Ray workers over one worker, and Ray's overhead per trial (one actor against
this process). The trials must be identical for the same number of workers.

    python -m benchmarks.bench_ray [--trials 32] [--method random]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from benchmarks._timing import Row, print_table
from stl_lfd.optim import RunDirectory, Trial, finish_run, load_task, start_run

ROOT = Path(__file__).resolve().parent.parent


def timed_run(task, folder: Path, ray: str | None = None) -> tuple[float, list[Trial]]:
    """The wall time of the run's trials (not of its unoptimised execution, which runs in this
    process in every case) and its trials' records."""
    prepared = start_run(task, folder)
    start = time.perf_counter()
    with prepared:
        finish_run(prepared, ray=ray)
    seconds = time.perf_counter() - start
    return seconds, RunDirectory(folder).trials()


def same_trials(first: list[Trial], second: list[Trial]) -> bool:
    return [(t.x.tolist(), t.robustness) for t in first] == [(t.x.tolist(), t.robustness) for t in second]


def start_up_seconds(task, workers: int) -> float:
    """How much longer the first batch of `workers` trials takes on Ray than the next one: the
    worker processes build their PyBullet worlds (and import stlopt, in a new process)."""
    import numpy as np

    from stl_lfd.optim import ObjectiveFactory, RayPool, build_search_space, resolve, task_models

    models = task_models(resolve(task))
    x = np.asarray(build_search_space(models, task.parameters, task.source).bounds, dtype=float).mean(axis=0)
    pool = RayPool(ObjectiveFactory(resolve(task), models), "auto")  # the local Ray started in main
    batches = []
    for first in (1, 1 + workers):
        start = time.perf_counter()
        pool([(x, first + offset) for offset in range(workers)])()
        batches.append(time.perf_counter() - start)
    pool.close()
    return batches[0] - batches[1]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=32, help="trials per run")
    parser.add_argument("--method", default=None, help="search method (default: the task's, plan)")
    arguments = parser.parse_args(argv)
    import ray

    task = load_task(ROOT / "configs" / "phi1.yaml").with_overrides(trials=arguments.trials, initial=min(8, arguments.trials), method=arguments.method)
    ray.init(address="local", num_cpus=2, include_dashboard=False, log_to_driver=False)  # a new Ray, not a cluster running here
    try:
        with tempfile.TemporaryDirectory() as folder:
            one, one_trials = timed_run(task, Path(folder) / "one")
            ray_one, ray_one_trials = timed_run(task, Path(folder) / "ray-one", ray="auto")  # the local Ray started above
            start_one, start_two = start_up_seconds(task, 1), start_up_seconds(task, 2)
            two = task.with_overrides(workers=2)
            local_two, local_two_trials = timed_run(two, Path(folder) / "local-two")
            ray_two, ray_two_trials = timed_run(two, Path(folder) / "ray-two", ray="auto")  # the local Ray started above
    finally:
        ray.shutdown()
    same = same_trials(one_trials, ray_one_trials) and same_trials(local_two_trials, ray_two_trials)
    trials = arguments.trials
    proposing = sum(t.optimizer_seconds for t in one_trials)
    per_trial = (ray_one - start_one - one) / trials
    print_table(
        f"Trials on Ray (phi1, PyBullet, method {task.optimizer.method}, {trials} trials, seed 0, local Ray of 2 CPUs; "
        f"trials identical for the same workers: {'yes' if same else 'NO'})",
        [
            Row("1 worker, this process", f"{trials} trials", one / trials, None, f"{one:.1f} s, of which proposing {proposing:.1f} s"),
            Row("1 Ray worker", f"{trials} trials", ray_one / trials, None, f"{ray_one:.1f} s"),
            Row("Ray start-up", "1 / 2 workers", start_one, None, f"{start_one:.1f} s / {start_two:.1f} s: the first batch's worlds"),
            Row("Ray overhead", "per trial", per_trial, None, "1 Ray worker less start-up, against this process"),
            Row("2 local workers", f"{trials} trials", local_two / trials, None, f"{one / local_two:.2f}x faster than 1 worker"),
            Row("2 Ray workers", f"{trials} trials", ray_two / trials, None, f"{one / ray_two:.2f}x faster than 1 worker"),
        ],
    )
    if not same:
        sys.exit("Ray gave other trials than the local workers")


if __name__ == "__main__":
    main()
