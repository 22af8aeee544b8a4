"""Method `plan`'s cost: plans per second, scored together (one batched retrieval) against one
at a time; and inside real runs, the optimiser's seconds per trial and its first proposal (the
design search, 256 plans) against the same run's rollouts.

    python -m benchmarks.bench_plan [--runs phi1 phi2 phi3_strict until_l4] [--plans 128]

Every ratio is measured within one run (or one process), so that the machine's load weighs on
both sides alike. The runs are the bundled phi1, phi2 and phi3_strict tasks on PyBullet and the
suite's `until_l4` (an unbounded until under the new semantics, whose plans are expensive to
score) on the kinematic backend, each with its own budget and seed 0. On PyBullet, method
`plan` checks after every trial whether the robot follows its plans (within 1 mm, it scores
the plans themselves; otherwise through the robot's tracking model, predicting every
proposal's candidates anew); each PyBullet run is also made `untracked` (the plan as it stands,
`benchmarks.bench_suite.untracked`, never checked), whose plans are memoised for the run.
"""

from __future__ import annotations

import argparse
import contextlib
import statistics
import tempfile
import time
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from benchmarks._timing import Row, print_table

ROOT = Path(__file__).resolve().parent.parent
RUNS = {
    "phi1": (ROOT / "configs" / "phi1.yaml", "pybullet"),
    "phi2": (ROOT / "configs" / "phi2.yaml", "pybullet"),
    "phi3_strict": (ROOT / "configs" / "phi3_strict.yaml", "pybullet"),
    "until_l4": (ROOT / "benchmarks" / "problems" / "until_l4.yaml", "kinematic"),
}
MEDIAN_TARGET = 0.5  # the optimiser's median seconds per trial, in rollouts
FIRST_TARGET = 2.0  # the first proposal, in rollouts
UNTIL_TARGET = 1.0  # seconds: until_l4's plan proposal


def plans_per_second(count: int) -> tuple[float, float]:
    """Plans per second of phi1's objective (kinematic), `count` points scored in one batch and
    `count` other points one at a time (after a warm-up of both)."""
    from stl_lfd.optim import load_task, objective_for, resolve, task_models

    task = load_task(RUNS["phi1"][0]).with_overrides(backend="kinematic")
    space, objective = objective_for(resolve(task), task_models(resolve(task)))
    score = objective.plan_score()
    unit = np.random.default_rng(0).random((2 * count + 8, space.dimension))
    batched, alone, warm = (space.lower + part * (space.upper - space.lower) for part in (unit[:count], unit[count : 2 * count], unit[2 * count :]))
    score(warm)
    score(warm[:1])
    start = time.perf_counter()
    score(batched)
    middle = time.perf_counter()
    for x in alone:
        score(x[None])
    return count / (middle - start), count / (time.perf_counter() - middle)


@dataclass(frozen=True)
class RunTiming:
    """Timings of one run of method `plan`: medians over its trials, and trial 1's proposal."""

    name: str
    backend: str
    untracked: bool
    trials: int
    optimizer_median: float
    rollout_median: float
    first_proposal: float


def run_timing(name: str, untracked: bool = False) -> RunTiming:
    """Run the task `name` of RUNS with method plan (`untracked`: scoring the plan as it stands)
    and read its trials' timings."""
    from benchmarks.bench_suite import untracked as plan_as_it_stands
    from stl_lfd.optim import RunDirectory, finish_run, load_task, start_run

    path, backend = RUNS[name]
    task = load_task(path).with_overrides(method="plan", backend=backend, seed=0)
    with tempfile.TemporaryDirectory() as folder, warnings.catch_warnings(), plan_as_it_stands() if untracked else contextlib.nullcontext():
        warnings.simplefilter("ignore")
        with start_run(task, Path(folder) / "run") as prepared:
            finish_run(prepared)
        trials = RunDirectory(Path(folder) / "run").trials()
    proposals = [trial.optimizer_seconds for trial in trials]
    rollouts = [trial.rollout_seconds for trial in trials]
    return RunTiming(name, backend, untracked, len(trials), statistics.median(proposals), statistics.median(rollouts), proposals[0])


def rows(batched: float, alone: float, count: int, runs: list[RunTiming]) -> list[Row]:
    """The table: plans per second, then per run the median proposal and the first one."""
    table = [
        Row(
            "plan, batched vs alone",
            f"phi1, {count} plans, kinematic",
            1 / batched,
            1 / alone,
            f"{batched:.0f} plans/s batched, {alone:.0f} one at a time: {batched / alone:.1f}x",
        )
    ]
    for run in runs:
        size = f"{run.name}, {run.backend}{', untracked' if run.untracked else ''}, {run.trials} trials"
        if run.backend == "kinematic":  # a rollout is the plan itself: the target is absolute
            median_target, first_target = UNTIL_TARGET, UNTIL_TARGET
        else:
            median_target, first_target = MEDIAN_TARGET * run.rollout_median, FIRST_TARGET * run.rollout_median
        ratio = f"rollout {run.rollout_median:.2f} s/trial"
        table.append(
            Row("plan optimiser per trial", size, run.optimizer_median, median_target, f"{run.optimizer_median / run.rollout_median:.2f}x the {ratio}")
        )
        table.append(Row("plan first proposal", size, run.first_proposal, first_target, f"{run.first_proposal / run.rollout_median:.1f} rollouts ({ratio})"))
    return table


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", nargs="*", default=list(RUNS), choices=list(RUNS))
    parser.add_argument("--plans", type=int, default=128, help="plans timed each way")
    args = parser.parse_args(argv)
    batched, alone = plans_per_second(args.plans)
    runs = [run_timing(name, untracked) for name in args.runs for untracked in ((False, True) if RUNS[name][1] == "pybullet" else (False,))]
    print_table("Method plan: plans and proposals", rows(batched, alone, args.plans, runs))


if __name__ == "__main__":
    main()
