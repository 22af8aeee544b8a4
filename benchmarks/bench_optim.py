"""Optimisation: optimiser overhead per trial (GP fit + acquisition), timed inside a real phi2
run with the PyBullet backend against that run's rollouts, and on a synthetic history of 30
trials and 21 parameters; a whole 32-trial phi1 run; and, over seeds, trials to first
satisfaction and best robustness of stl, PI, LogEI and random search on phi1 and phi2.

    python -m benchmarks.bench_optim [--backend kinematic|pybullet] [--seeds 5] [--semantics new]

`make bench` runs the comparison on the kinematic backend (the same skill, tracked to
0.05 mm by PyBullet, without the simulation's 0.4 s per trial); pass `--backend pybullet` for
the acceptance figures.
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.table import Table

from benchmarks._timing import Row, print_table
from stl_lfd.optim import Optimizer, RunDirectory, finish_run, load_task, local_map, start_run
from stl_lfd.optim.methods import ProbabilityOfImprovement, Problem, Request

ROOT = Path(__file__).resolve().parent.parent
# Workers are spawned, not forked: forking after torch or pybullet started threads deadlocks.
METHODS = ("stl", "pi", "logei", "random")


def overhead_seconds(repeats: int = 7) -> float:
    """Median time of one proposal (GP fit + PI maximisation) at n = 30, d = 21."""
    rng = np.random.default_rng(0)
    bounds = np.vstack([np.zeros(21), np.ones(21)])
    X = rng.random((30, 21))
    Y = -np.linalg.norm(X - 0.3, axis=1) + 0.01 * rng.standard_normal(30)
    method = ProbabilityOfImprovement(Problem(bounds), Optimizer(method="pi", initial=1, trials=100))
    method.search(Request([], np.empty((0, 21)), 30, 1, 0), X, Y)
    times = []
    for seed in range(repeats):
        start = time.perf_counter()
        method.search(Request([], np.empty((0, 21)), 30, 1, seed), X, Y)
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def one_run(arguments: tuple[str, str, str, str, int]) -> dict:
    spec, method, semantics, backend, seed = arguments
    warnings.simplefilter("ignore")
    from dataclasses import replace

    task = load_task(ROOT / "configs" / f"{spec}.yaml").with_overrides(method=method, backend=backend, seed=seed)
    task = replace(task, semantics=semantics)
    with tempfile.TemporaryDirectory() as folder:
        summary = finish_run(start_run(task, Path(folder) / "run"))
        trials = RunDirectory(Path(folder) / "run").trials()
    proposed = [trial.optimizer_seconds for trial in trials if trial.phase != "sobol"]
    timing = {"optimizer_median": statistics.median(proposed), "rollout_median": statistics.median(trial.rollout_seconds for trial in trials)}
    return summary.to_json() | timing | {"spec": spec, "method": method}


def comparison(backend: str, seeds: int, semantics: str, workers: int = 2) -> list[dict]:
    jobs = [(spec, method, semantics, backend, seed) for spec in ("phi1", "phi2") for method in METHODS for seed in range(seeds)]
    results = dict(local_map(one_run, jobs, workers))
    return [results[job] for job in jobs]


def print_comparison(results: list[dict], backend: str, semantics: str) -> None:
    table = Table(title=f"Optimisation over seeds ({backend} backend, {semantics} robustness, 32 trials: 8 Sobol + method)", title_justify="left")
    for column in ("spec", "method", "satisfied", "first satisfied (per seed)", "mean first", "best robustness (median)", "initial", "run time (median)"):
        table.add_column(column)
    for spec in ("phi1", "phi2"):
        for method in METHODS:
            rows = [r for r in results if r["spec"] == spec and r["method"] == method]
            firsts = [r["first_satisfied_trial"] for r in rows]
            found = [f for f in firsts if f is not None]
            # a seed that never satisfies counts as budget + 1 in the mean
            mean_first = statistics.mean(f if f is not None else r["budget"] + 1 for f, r in zip(firsts, rows))
            table.add_row(
                spec,
                method,
                f"{len(found)}/{len(rows)}",
                " ".join(str(f) if f is not None else "-" for f in firsts),
                f"{mean_first:.1f}",
                f"{statistics.median(r['best_robustness'] for r in rows):+.4f}",
                f"{rows[0]['initial_robustness']:+.4f}",
                f"{statistics.median(r['wall_seconds'] for r in rows):.1f} s",
            )
    Console(width=150).print(table)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--backend", default="kinematic", choices=("kinematic", "pybullet"))
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--semantics", default="new", choices=("new", "classic"))
    args = parser.parse_args(argv)
    overhead = overhead_seconds()
    inside = one_run(("phi2", "stl", "new", "pybullet", 0))
    start = time.perf_counter()
    whole = one_run(("phi1", "stl", "new", "pybullet", 0))
    whole_seconds = time.perf_counter() - start
    print_table(
        "Optimiser timing",
        [
            Row(
                "stl overhead per trial",
                "median inside a phi2 pybullet run",
                inside["optimizer_median"],
                inside["rollout_median"],
                "target: the run's median rollout",
            ),
            Row("pi overhead per trial", "GP fit + PI, synthetic n = 30, d = 21", overhead, 0.5),
            Row("phi1 run, pybullet, stl", "learn + initial + 32 trials", whole_seconds, 120.0, f"best {whole['best_robustness']:+.4f}"),
        ],
    )
    print_comparison(comparison(args.backend, args.seeds, args.semantics), args.backend, args.semantics)


if __name__ == "__main__":
    main()
