"""Sim-to-sim transfer: the best trial a run finds on one engine, executed on the other.

For each task and seed, a run optimises on the source engine (the task as bundled, with its
backend replaced); its best trial's skill is then executed once on the target engine at the
run's placement and scored by the same spec (semantics, nu). A transfer holds when the target
execution still satisfies the spec. On the contact tasks the target execution is also checked
physically (`benchmarks.physical`: the shaft ends in the hole, never flung).

    python -m benchmarks.bench_transfer [--tasks phi1,phi2,phi3_reorient] [--seeds 0-9]
        [--directions pybullet:mujoco,mujoco:pybullet] [--jobs 1] [--robot LABEL]
        [--out benchmarks/results/transfer.jsonl]

One JSON line per run (task, direction, seed) is appended to --out, with the commit and the
robot's label (the results page keeps robots apart). About one to three minutes per
free-space run and five to fifteen per phi3_reorient run on one core.
"""

from __future__ import annotations

import argparse
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any

from benchmarks._records import commit, recorded_results, seed_list
from benchmarks.physical import flung, holder_pose, scene_geometry, shaft_end

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results" / "transfer.jsonl"
TASKS = ("phi1", "phi2", "phi3_reorient")
DIRECTIONS = ("pybullet:mujoco", "mujoco:pybullet")
ROBOT = "compliant, stiff fingertips"


def one_transfer(job: tuple[str, str, str, int]) -> dict[str, Any]:
    """Optimise `task_name` on `source` with `seed`, then execute its best trial on `target`."""
    task_name, source, target, seed = job
    warnings.simplefilter("ignore")
    from stl_lfd.optim import finish_run, load_task, objective_for, resolve, start_run, trial_skill

    task = load_task(ROOT / "configs" / f"{task_name}.yaml").with_overrides(seed=seed, backend=source)
    start = time.perf_counter()
    result: dict[str, Any] = {"task": task_name, "source": source, "target": target, "seed": seed}
    with tempfile.TemporaryDirectory() as folder:
        summary = finish_run(start_run(task, Path(folder) / "run"))
        result["source_robustness"] = summary.best_robustness
        if summary.best_trial is None:
            return result | {"target_robustness": None, "wall_seconds": round(time.perf_counter() - start, 1)}
        best = trial_skill(Path(folder) / "run", "best")
    result["best_trial"] = best.trial
    _, objective = objective_for(resolve(task.with_overrides(backend=target)), best.models)
    try:
        outcome = objective.evaluate(best.models)
    finally:
        objective.close()
    result["target_robustness"] = outcome.robustness
    signals = outcome.payload
    if signals is not None and "shaft_x" in signals.columns:
        result["target_physically_inserted"] = shaft_end(signals, holder_pose(task), scene_geometry(task.scene)) == "inserted" and not flung(signals)
    return result | {"wall_seconds": round(time.perf_counter() - start, 1)}


def satisfied(value: float | None) -> bool:
    return value is not None and value > 0


def transfer_counts(runs: list[dict[str, Any]]) -> tuple[int, int, list[bool]]:
    """Of one (task, source, target) group's runs: how many satisfied their spec on the source,
    how many of those still satisfy it on the target, and for each of those checked physically
    whether the shaft ended in the hole on the target (the console table's and the page's counts)."""
    on_source = [run for run in runs if satisfied(run["source_robustness"])]
    kept = sum(satisfied(run["target_robustness"]) for run in on_source)
    inserted = [run["target_physically_inserted"] for run in on_source if "target_physically_inserted" in run]
    return len(on_source), kept, inserted


def print_totals(results: list[dict[str, Any]], title: str) -> None:
    """Per task and direction, over seeds."""
    from rich.console import Console
    from rich.table import Table

    table = Table(title=title, title_justify="left")
    for column in ("task", "from", "to", "seeds", "satisfied on source", "still satisfied on target", "physically inserted on target", "time"):
        table.add_column(column, justify="left" if column in ("task", "from", "to") else "right")
    groups: dict[tuple[str, str, str], list[dict[str, Any]]] = {}
    for result in results:
        groups.setdefault((result["task"], result["source"], result["target"]), []).append(result)
    for (task_name, source, target), runs in groups.items():
        on_source, kept, inserted = transfer_counts(runs)
        minutes = sum(run["wall_seconds"] for run in runs) / 60
        table.add_row(
            task_name,
            source,
            target,
            str(len(runs)),
            f"{on_source}/{len(runs)}",
            f"{kept}/{on_source}",
            f"{sum(inserted)}/{len(inserted)}" if inserted else "",
            f"{minutes:.1f} min",
        )
    Console(width=160).print(table)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", default=",".join(TASKS))
    parser.add_argument("--seeds", default="0-9", help="e.g. 0-9, 3 or 0-4,7")
    parser.add_argument("--directions", default=",".join(DIRECTIONS), help="SOURCE:TARGET engine pairs")
    parser.add_argument("--jobs", type=int, default=1, help="runs side by side (spawned processes)")
    parser.add_argument("--robot", default=ROBOT, help=f"a label of the robots and their control, recorded with each line (default: {ROBOT!r})")
    parser.add_argument("--out", type=Path, default=RESULTS, help="the JSON-lines file the results are appended to")
    args = parser.parse_args(argv)
    jobs = [(task, *direction.split(":"), seed) for task in args.tasks.split(",") for direction in args.directions.split(",") for seed in seed_list(args.seeds)]
    results, start = [], time.perf_counter()
    for line in recorded_results(one_transfer, jobs, args.jobs, args.out, {"commit": commit(), "robot": args.robot}):
        results.append(line)
        print(
            f"{line['task']} {line['source']} -> {line['target']} seed {line['seed']}: "
            f"{line['source_robustness']} -> {line['target_robustness']} ({line['wall_seconds']:.0f} s)",
            flush=True,
        )
    results.sort(key=lambda line: jobs.index((line["task"], line["source"], line["target"], line["seed"])))
    print_totals(results, f"Sim-to-sim transfer of the best trial ({time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
