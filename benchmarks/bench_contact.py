"""Where the shaft ends on the contact tasks (phi3, phi3_reorient and phi3_reorient_one by
default; phi3_inserted with --tasks): an independent physical check of every trial of short optimisation runs,
the unoptimised trial included, read from the run directory's recorded shaft and holder poses
(not from the outcome signals the specs use), against the spec's verdict.

    python -m benchmarks.bench_contact [--tasks phi3,phi3_reorient,phi3_reorient_one]
        [--seeds 0-9] [--methods plan,random] [--trials 16] [--backend pybullet] [--jobs 1]
        [--robot LABEL] [--out benchmarks/results/contact.jsonl]

Each trial's end is classified by `benchmarks.physical` (thrown, inserted, other; flung on
the way; physically inserted). A trial that failed (no signals) is counted apart. Satisfied:
robustness > 0 as the run recorded it; the verdict AGREES with the check when satisfied ==
physically inserted. For the inserted trials the spec rejects, the spec's failing parts are
counted. One JSON line per run (task, method, seed) is appended to --out, with the commit.
About 1-2 s per rollout on one core: 17 rollouts a run, 60 runs by default.
"""

from __future__ import annotations

import argparse
import tempfile
import time
import warnings
from collections import Counter
from pathlib import Path
from typing import Any

from benchmarks._records import commit, recorded_results, seed_list
from benchmarks.physical import end_offset, flung, holder_pose, scene_geometry, shaft_end

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results" / "contact.jsonl"
TASKS = ("phi3", "phi3_reorient", "phi3_reorient_one")
CLASSES = ("thrown", "inserted", "other", "failed")


def one_run(job: tuple[str, str, int, int, str]) -> dict[str, Any]:
    """Optimise `task` with `method` and `seed` for `trials` trials on `backend`, and classify
    the end of every trial (the unoptimised one first)."""
    task_name, method, seed, trials, backend = job
    warnings.simplefilter("ignore")
    from stl_lfd.optim import RunDirectory, finish_run, load_task, start_run

    task = load_task(ROOT / "configs" / f"{task_name}.yaml").with_overrides(seed=seed, method=method, trials=trials, backend=backend)
    start = time.perf_counter()
    with tempfile.TemporaryDirectory() as folder:
        summary = finish_run(start_run(task, Path(folder) / "run"))
        run = RunDirectory(Path(folder) / "run")
        holder = holder_pose(task)
        trials = run.trials()
        robustness = [summary.initial_robustness] + [trial.robustness for trial in trials]
        components = [summary.initial_components or {}] + [trial.components or {} for trial in trials]
        ends, thrown_up, offsets = [], [], []
        for number in range(len(robustness)):
            signals = run.recorded_signals(number)
            ends.append("failed" if signals is None else shaft_end(signals, holder, scene_geometry(task.scene)))
            thrown_up.append(signals is not None and flung(signals))
            offsets.append(end_offset(signals) if signals is not None else float("nan"))
    satisfied = [value is not None and value > 0 for value in robustness]
    physical = [end == "inserted" and not up for end, up in zip(ends, thrown_up)]
    rejected = Counter(part for ok, inside, parts in zip(satisfied, physical, components) if inside and not ok for part, value in parts.items() if value <= 0)
    rejected_offsets = [round(1000 * offset, 1) for ok, inside, offset in zip(satisfied, physical, offsets) if inside and not ok]
    counts = Counter(ends)
    return {
        "task": task_name,
        "method": method,
        "seed": seed,
        "trials": len(ends),
        **{name: counts[name] for name in CLASSES},
        "satisfied": sum(satisfied),
        "satisfied_inserted": sum(ok and end == "inserted" for ok, end in zip(satisfied, ends)),
        "flung": sum(thrown_up),
        "physically_inserted": sum(physical),
        "satisfied_physically_inserted": sum(ok and inside for ok, inside in zip(satisfied, physical)),
        "agrees": sum(ok == inside for ok, inside in zip(satisfied, physical)),
        "best_satisfied": bool(summary.best_robustness is not None and summary.best_robustness > 0),
        "best_physically_inserted": bool(summary.best_trial is not None and physical[summary.best_trial]),
        "rejected_inserted": dict(rejected),
        "rejected_offsets_mm": rejected_offsets,  # where each of those shafts ends, from the hole's axis
        "ends": "".join(end[0].upper() for end in ends),  # per trial from the unoptimised one: T, I, O, F
        "wall_seconds": round(time.perf_counter() - start, 1),
    }


def print_totals(results: list[dict[str, Any]], title: str) -> None:
    """Per task and method, summed over seeds."""
    from rich.console import Console
    from rich.table import Table

    table = Table(title=title, title_justify="left")
    columns = (
        "task",
        "method",
        "seeds",
        "trials",
        "thrown",
        "inserted",
        "other",
        "failed",
        "flung",
        "phys. inserted",
        "satisfied",
        "satisfied & phys. inserted",
        "agrees",
        "runs satisfied",
        "best inserted",
        "time",
    )
    for column in columns:
        table.add_column(column, justify="left" if column in ("task", "method") else "right")
    groups: dict[tuple[str, str], list[dict[str, Any]]] = {}
    for result in results:
        groups.setdefault((result["task"], result["method"]), []).append(result)
    for (task_name, method), runs in groups.items():
        keys = ("trials", *CLASSES, "flung", "physically_inserted", "satisfied", "satisfied_physically_inserted", "agrees")
        total = {key: sum(run[key] for run in runs) for key in (*keys, "wall_seconds")}
        counts = [str(total[key]) for key in keys]
        best = [str(sum(run[key] for run in runs)) for key in ("best_satisfied", "best_physically_inserted")]
        table.add_row(task_name, method, str(len(runs)), *counts, *best, f"{total['wall_seconds'] / 60:.1f} min")
    console = Console(width=200)
    console.print(table)
    for (task_name, method), runs in groups.items():
        rejected = sum((Counter(run["rejected_inserted"]) for run in runs), Counter())
        if rejected:
            console.print(
                f"{task_name} {method}: failing parts of the physically inserted trials the spec rejects: "
                + "; ".join(f"{part} ({count})" for part, count in rejected.most_common())
            )


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tasks", default=",".join(TASKS))
    parser.add_argument("--seeds", default="0-9", help="e.g. 0-9, 3 or 0-4,7")
    parser.add_argument("--methods", default="plan,random")
    parser.add_argument("--trials", type=int, default=16, help="optimised trials per run (the unoptimised one comes on top)")
    parser.add_argument("--backend", default="pybullet")
    parser.add_argument("--jobs", type=int, default=1, help="runs side by side (spawned processes)")
    parser.add_argument("--robot", default=None, help="a label of the robot and its control, recorded with each line (default: the backend)")
    parser.add_argument("--out", type=Path, default=RESULTS, help="the JSON-lines file the results are appended to")
    args = parser.parse_args(argv)
    jobs = [
        (task, method, seed, args.trials, args.backend)
        for task in args.tasks.split(",")
        for method in args.methods.split(",")
        for seed in seed_list(args.seeds)
    ]
    stamp = {"commit": commit(), "backend": args.backend, "robot": args.robot or args.backend}
    results, start = [], time.perf_counter()
    for line in recorded_results(one_run, jobs, args.jobs, args.out, stamp):
        results.append(line)
        print(f"{line['task']} {line['method']} seed {line['seed']}: {line['ends']} ({line['wall_seconds']:.0f} s)", flush=True)
    results.sort(key=lambda line: jobs.index((line["task"], line["method"], line["seed"], args.trials, args.backend)))
    print_totals(results, f"Where the shaft ends ({stamp['robot']}, {args.trials} trials + the unoptimised one, {time.perf_counter() - start:.0f} s)")


if __name__ == "__main__":
    main()
