"""phi3 over seeds on a simulated Panda: satisfaction, trials to first satisfaction, peak
contact force over the holder and the time the pick reaches the shaft, before and after, and
how many pick states the best behaviour still visits.

    python -m benchmarks.bench_phi3 [--specs phi3_strict,phi3] [--seeds 5] [--backend mujoco]

About 4 minutes per spec on 2 cores (two runs side by side).
"""

from __future__ import annotations

import argparse
import tempfile
import warnings
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.table import Table

from stl_lfd import read_signal_csv
from stl_lfd.optim import RunDirectory, finish_run, load_task, local_map, start_run
from stl_lfd.report import followed_states
from stl_lfd.stl import load_spec, region_boxes

ROOT = Path(__file__).resolve().parent.parent
# Workers are spawned, not forked: forking after torch or pybullet started threads deadlocks.


def inside(table, box) -> np.ndarray:
    return np.all([(table.columns[name] >= lo) & (table.columns[name] <= hi) for name, (lo, hi) in box.items()], axis=0)


def insertion_and_pick(path: Path) -> tuple[float, float | None]:
    """Peak force while the hand is over the holder, and the first time it is at the shaft."""
    regions = region_boxes(load_spec(ROOT / "specs" / "pick_insert.stl"))
    table = read_signal_csv(path)
    over, at_shaft = inside(table, regions["HOLDER"]), inside(table, regions["OBJECT"])
    peak = float(table.columns["force"][over].max()) if over.any() else 0.0
    return peak, float(table.times[at_shaft][0]) if at_shaft.any() else None


def one_run(arguments: tuple[str, int, str | None]) -> dict:
    spec, seed, backend = arguments
    warnings.simplefilter("ignore")
    task = load_task(ROOT / "configs" / f"{spec}.yaml").with_overrides(seed=seed, backend=backend)
    with tempfile.TemporaryDirectory() as folder:
        summary = finish_run(start_run(task, Path(folder) / "run"))
        run = RunDirectory(Path(folder) / "run")
        before = insertion_and_pick(run.signals_path(0))
        best = summary.best_trial
        after = insertion_and_pick(run.signals_path(best)) if best else (None, None)
        visited = len(followed_states(run.best_models()["pick"])) if best else None
    return summary.to_json() | {"spec": spec, "before": before, "after": after, "visited": visited}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--specs", default="phi3_strict,phi3")
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--backend", default=None, help="the simulator (default: each task's)")
    args = parser.parse_args(argv)
    jobs = [(spec, seed, args.backend) for spec in args.specs.split(",") for seed in range(args.seeds)]
    finished = dict(local_map(one_run, jobs, 2))
    results = [finished[job] for job in jobs]
    engine = args.backend or "each task's backend"
    table = Table(title=f"phi3 over seeds ({engine}; the tasks' trials and methods)", title_justify="left")
    for column in ("spec", "seed", "satisfied", "first", "peak force before → after (N)", "pick at shaft before → after (s)", "pick states", "time"):
        table.add_column(column)
    for r in results:
        after_force = "-" if r["after"][0] is None else f"{r['after'][0]:.1f}"
        after_pick = "-" if r["after"][1] is None else f"{r['after'][1]:.1f}"
        table.add_row(
            r["spec"],
            str(r["seed"]),
            "yes" if r["satisfied"] else "no",
            str(r["first_satisfied_trial"] or "-"),
            f"{r['before'][0]:.1f} → {after_force}",
            f"{r['before'][1]:.1f} → {after_pick}",
            str(r["visited"]),
            f"{r['wall_seconds']:.0f} s",
        )
    Console(width=150).print(table)


if __name__ == "__main__":
    main()
