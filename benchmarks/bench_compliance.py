"""The compliant Panda against the real robot's figures: how closely it follows the bundled free-
space skills, what its wrist reads in free motion, and what the unoptimised phi3 insertion
(which meets the holder's edge) reads, on each simulator.

    python -m benchmarks.bench_compliance [--engines pybullet,mujoco]

The targets: phi1's and phi2's references followed within 5 mm RMS; free motion read under
1 N; the unoptimised phi3 insertion's peak force over the holder between 5 and 60 N, as a
real Panda with a wrist sensor would show (a position-controlled arm read over 100 N). Results
are appended to `benchmarks/results/compliance.jsonl`.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import warnings
from pathlib import Path

from rich.console import Console
from rich.table import Table

from benchmarks._records import commit
from benchmarks.bench_phi3 import insertion_and_pick
from stl_lfd import write_signal_csv
from stl_lfd.optim import load_task, objective_for, resolve, task_models
from stl_lfd.sim import TrackingWarning, new_backend

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results" / "compliance.jsonl"
FREE_SPACE_TASKS = ("phi1", "phi2")
CONTACT_TASK = "phi3"


def unoptimised_rollout(task_name: str, engine: str):
    """The task's skill as learned, executed once on `engine`."""
    task = load_task(ROOT / "configs" / f"{task_name}.yaml").with_overrides(backend="kinematic")
    _, objective = objective_for(resolve(task), task_models(resolve(task)))
    placed = objective.placed[0]
    with new_backend(engine) as backend, warnings.catch_warnings():
        warnings.simplefilter("ignore", TrackingWarning)
        return placed.execute(backend, task.rate)


def measure(engine: str, folder: Path) -> list[dict]:
    rows = []
    for name in FREE_SPACE_TASKS:
        rollout = unoptimised_rollout(name, engine)
        force = rollout.signals.columns["force"]
        rows.append(
            {"task": name, "tracking_rms_mm": 1000 * rollout.tracking_rms, "tracking_max_mm": 1000 * rollout.tracking_max, "force_max_n": float(force.max())}
        )
    rollout = unoptimised_rollout(CONTACT_TASK, engine)
    path = folder / f"{CONTACT_TASK}-{engine}.csv"
    write_signal_csv(rollout.signals, path)
    peak, _ = insertion_and_pick(path)
    rows.append({"task": CONTACT_TASK, "insertion_peak_n": peak, "force_max_n": float(rollout.signals.columns["force"].max())})
    return [{"engine": engine} | row for row in rows]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default="pybullet,mujoco")
    args = parser.parse_args(argv)
    table = Table(title="The compliant Panda: tracking, free motion, the unoptimised phi3 insertion", title_justify="left")
    for column in ("engine", "task", "tracking RMS / max", "force max", "insertion peak", "target"):
        table.add_column(column)
    with tempfile.TemporaryDirectory() as folder:
        rows = [row for engine in args.engines.split(",") for row in measure(engine, Path(folder))]
    with RESULTS.open("a") as results:
        for row in rows:
            results.write(json.dumps({"commit": commit()} | row) + "\n")
    for row in rows:
        if "tracking_rms_mm" in row:
            verdict = "ok" if row["tracking_rms_mm"] < 5 and row["force_max_n"] < 1 else "MISSED"
            table.add_row(
                row["engine"],
                row["task"],
                f"{row['tracking_rms_mm']:.2f} / {row['tracking_max_mm']:.2f} mm",
                f"{row['force_max_n']:.2f} N",
                "",
                f"< 5 mm RMS, < 1 N: {verdict}",
            )
        else:
            verdict = "ok" if 5 <= row["insertion_peak_n"] <= 60 else "MISSED"
            table.add_row(row["engine"], row["task"], "", f"{row['force_max_n']:.1f} N", f"{row['insertion_peak_n']:.1f} N", f"5-60 N: {verdict}")
    Console().print(table)


if __name__ == "__main__":
    main()
