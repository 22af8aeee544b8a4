"""Recorded trials that the optimiser must keep giving: a run of each case, its phases and points.

    python -m tests.optim.same_trials --write    # record the cases anew (after a deliberate change)

The record (`data/same_trials.json`) names the processor it was made on: the trials a Gaussian
process decides depend on how its numerics round, which differs between kinds of processor
(numpy and torch pick their kernels by the vector instructions there are). So on another kind
only the trials that no model decides (the initial design, Sobol and random points) are compared.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import warnings
from pathlib import Path

import numpy as np

from tests.conftest import ROOT

RECORD = Path(__file__).parent / "data" / "same_trials.json"
MODEL_FREE_PHASES = ("design", "sobol", "random")

# (name, task file, overrides): kinematic suite problems under every method, the lagging robot
# (method plan's difference GP), two workers (batches), and the bundled PyBullet tasks.
CASES = [
    (f"{problem}/{method}", f"benchmarks/problems/{problem}.yaml", {"backend": "kinematic", "method": method, "initial": 4, "trials": 7, "seed": 3})
    for problem in ("phi1_first", "phi2_seed12", "hold_l3")
    for method in ("plan", "stl", "pi", "logei", "random")
] + [
    (
        "phi1_first+lag/plan",
        "benchmarks/problems/phi1_first.yaml",
        {"backend": "kinematic", "method": "plan", "initial": 3, "trials": 6, "seed": 1, "lag": True},
    ),
    (
        "phi2_first/stl/workers2",
        "benchmarks/problems/phi2_first.yaml",
        {"backend": "kinematic", "method": "stl", "initial": 4, "trials": 8, "seed": 2, "workers": 2},
    ),
    (
        "phi2_first/plan/workers2",
        "benchmarks/problems/phi2_first.yaml",
        {"backend": "kinematic", "method": "plan", "initial": 4, "trials": 8, "seed": 2, "workers": 2},
    ),
    ("phi1/plan/pybullet", "configs/phi1.yaml", {"trials": 12}),
    ("phi2/plan/pybullet", "configs/phi2.yaml", {"trials": 12}),
]


def run_case(task_file: str, overrides: dict) -> list[dict]:
    """The trials (phase, point, robustness) of the task file's run with `overrides` (`lag`: on
    the suite's lagging robot)."""
    from benchmarks.bench_suite import executed_as
    from stl_lfd.optim import finish_run, load_task, start_run

    overrides = dict(overrides)
    lag = overrides.pop("lag", False)
    task = load_task(ROOT / task_file).with_overrides(**overrides)
    task = executed_as("x+lag", task) if lag else task
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as folder:
        with start_run(task, Path(folder) / "run") as prepared:
            finish_run(prepared)
        lines = (Path(folder) / "run" / "trials.jsonl").read_text().splitlines()
    return [{"phase": trial["phase"], "x": trial["x"], "robustness": trial["robustness"]} for trial in map(json.loads, lines)]


def differences(recorded: list[dict], trials: list[dict], model_free_only: bool = False) -> list[str]:
    """How `trials` differ from the `recorded` ones: phases, points (to 1e-9) and robustness."""
    if [trial["phase"] for trial in trials] != [trial["phase"] for trial in recorded]:
        return [f"phases {[trial['phase'] for trial in trials]} instead of {[trial['phase'] for trial in recorded]}"]
    found = []
    for number, (ours, theirs) in enumerate(zip(trials, recorded), start=1):
        if model_free_only and theirs["phase"] not in MODEL_FREE_PHASES:
            continue
        if not np.allclose(ours["x"], theirs["x"], rtol=0, atol=1e-9) or (ours["robustness"] is None) != (theirs["robustness"] is None):
            found.append(f"trial {number}: x {ours['x']} instead of {theirs['x']}")
        elif ours["robustness"] is not None and abs(ours["robustness"] - theirs["robustness"]) > 1e-9:
            found.append(f"trial {number}: robustness {ours['robustness']} instead of {theirs['robustness']}")
    return found


def main() -> None:
    from benchmarks.bench_suite import processor

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="record every case anew")
    parser.add_argument("--only", nargs="*", default=None, help="record only these cases")
    arguments = parser.parse_args()
    record = json.loads(RECORD.read_text()) if RECORD.exists() else {"processor": processor(), "cases": {}}
    record["processor"] = processor()
    for name, task_file, overrides in CASES:
        if arguments.only is None or name in arguments.only:
            trials = run_case(task_file, overrides)
            print(name, differences(record["cases"].get(name, []), trials) or "same trials")
            record["cases"][name] = trials
    if arguments.write:
        RECORD.write_text(json.dumps(record, indent=1) + "\n")


if __name__ == "__main__":
    main()
