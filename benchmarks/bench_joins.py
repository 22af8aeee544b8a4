"""Force at the joins of a behaviour: where one skill hands over to the next or to a gripper
action, how far the wrist's force rises above what it read just before, for the unoptimised
behaviour of each task on each engine (a real arm reads no spike there).

    python -m benchmarks.bench_joins [--tasks T ...] [--engines pybullet mujoco] [--label TEXT]

Each join's excess is the largest force in the 1 s after it (from 0.05 s before) minus the
median force over the 0.5 s before it; the table gives the largest excess of each task and
engine, with the join where it happens, and writes one line per (task, engine) to
`benchmarks/results/joins.jsonl`.
"""

from __future__ import annotations

import argparse
import json
import warnings
from pathlib import Path

import numpy as np

from benchmarks.bench_suite import task_file
from stl_lfd.optim import load_task, objective_for, resolve, task_models
from stl_lfd.sim import execute

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results" / "joins.jsonl"
TASKS = ("phi3", "phi3_reorient", "shelf", "stack", "tray", "peg")
BEFORE, AFTER, LEAD = 0.5, 1.0, 0.05  # s: the static window, the window after a join (a whole grasp), and its lead


def joins(skills: np.ndarray, times: np.ndarray) -> list[tuple[float, str]]:
    """`(time, 'A -> B')` of each sample where the reference's skill (or action) changes."""
    changes = np.flatnonzero(skills[1:] != skills[:-1]) + 1
    return [(float(times[index]), f"{skills[index - 1]} -> {skills[index]}") for index in changes]


def join_excesses(times: np.ndarray, force: np.ndarray, at: list[tuple[float, str]]) -> list[tuple[str, float]]:
    """Each join's force excess (N) above the median of the `BEFORE` seconds before it."""
    excesses = []
    for moment, label in at:
        before = force[(times >= moment - BEFORE) & (times < moment - LEAD)]
        after = force[(times >= moment - LEAD) & (times <= moment + AFTER)]
        if len(before) and len(after):
            excesses.append((label, float(np.max(after) - np.median(before))))
    return excesses


def measure(task_name: str, engine: str) -> dict:
    """The largest join excess of a task's unoptimised behaviour on `engine`."""
    task = load_task(task_file(task_name)).with_overrides(backend=engine)
    inputs = resolve(task)
    models = task_models(inputs)
    _, objective = objective_for(inputs, models, execute=False)
    reference = objective.reference(models)
    signals = execute(reference, objective.scene, engine, rate=task.rate).signals
    times, force = signals.times, np.asarray(signals.columns["force"])
    excesses = join_excesses(times, force, joins(np.asarray(reference.skills), reference.times))
    label, worst = max(excesses, key=lambda item: item[1]) if excesses else ("-", 0.0)
    return {"task": task_name, "engine": engine, "largest_excess_n": round(worst, 2), "at": label, "joins": {name: round(value, 2) for name, value in excesses}}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", nargs="+", default=list(TASKS))
    parser.add_argument("--engines", nargs="+", default=["pybullet", "mujoco"])
    parser.add_argument("--results", type=Path, default=RESULTS)
    parser.add_argument("--label", default="", help="what code is measured (kept in each record)")
    arguments = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    print(f"{'task':<16}{'engine':<10}{'largest excess (N)':>20}  at")
    for task_name in arguments.tasks:
        for engine in arguments.engines:
            record = {"code": arguments.label, **measure(task_name, engine)}
            with open(arguments.results, "a") as stream:
                stream.write(json.dumps(record) + "\n")
            print(f"{task_name:<16}{engine:<10}{record['largest_excess_n']:>20.2f}  {record['at']}", flush=True)


if __name__ == "__main__":
    main()
