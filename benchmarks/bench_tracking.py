"""The tracking model: how well it predicts a held-out execution from its reference, against the
plan (the reference itself) as the prediction.

    python -m benchmarks.bench_tracking [--points 8]

Executions: phi1 and phi2 on the PyBullet Panda, and phi1 on each robot of
`benchmarks.robots.VARIANTS` (a kinematic execution with a lag, sag, limits, clock, offset or
noise); each at the unoptimised skill and at `points - 1` Sobol points of the task's box. The
error is the RMS over the three axes of each execution predicted by a model fitted on the
others (leave one out). Targets: 1 mm on PyBullet; on the robots, 20 % of the plan's error
(none for noise, which nothing predicts).
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np
from rich.console import Console
from rich.table import Table
from torch.quasirandom import SobolEngine

from benchmarks.bench_suite import ROOT, LaggingBackend
from benchmarks.robots import VARIANTS
from stl_lfd.optim import load_task, objective_for, resolve, task_models
from stl_lfd.sim import Execution, TrackingModel

PYBULLET_TARGET = 0.001  # m
ROBOT_RATIO_TARGET = 0.2


def executions(task_name: str, points: int, backend=None) -> list[Execution]:
    """The executions of `task_name` (configs/) at the unoptimised skill and Sobol points, on
    the task's backend or on `backend`."""
    task = load_task(ROOT / "configs" / f"{task_name}.yaml")
    models = task_models(resolve(task))
    space, objective = objective_for(resolve(task), models)
    if backend is not None:
        objective.backend.close()
        objective.backend = backend
    unit = SobolEngine(space.dimension, scramble=True, seed=0).draw(points - 1).double().numpy()
    found = []
    try:
        for x in [space.initial, *(space.bounds[0] + unit * (space.bounds[1] - space.bounds[0]))]:
            adapted = space.apply(models, x)
            reference = objective.reference(adapted)
            signals = objective.evaluate(adapted).payload
            found.append(Execution(reference.times, reference.positions, signals.times, np.column_stack([signals.columns[axis] for axis in "xyz"])))
    finally:
        objective.close()
    return found


def row(case: str, found: list[Execution], target: float | None, ratio_target: float | None) -> list[str]:
    start = time.perf_counter()
    model = TrackingModel().fit(found)
    seconds = time.perf_counter() - start
    heldout, plan = float(np.sqrt(np.mean(model.heldout_rms_**2))), float(np.sqrt(np.mean(model.plan_rms_**2)))
    ratio = heldout / plan if plan > 0 else 0.0
    met = (target is None or heldout <= target) and (ratio_target is None or ratio <= ratio_target)
    wanted = " and ".join(([f"<= {1000 * target:g} mm"] if target else []) + ([f"<= {ratio_target:g} of the plan's"] if ratio_target else []))
    clock = f", clock {model.clock_:.3f}" if model.kind_ == "clocked filter" else ""
    return [
        case,
        str(len(found)),
        model.kind_ + clock,
        f"{1000 * heldout:.3f}",
        f"{1000 * plan:.3f}",
        f"{ratio:.3f}",
        wanted or "-",
        ("ok" if met else "MISSED") if wanted else "",
        f"{seconds:.2f} s",
    ]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=8, help="executions per case (default 8)")
    arguments = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    rows = [row(f"{name}, PyBullet", executions(name, arguments.points), PYBULLET_TARGET, None) for name in ("phi1", "phi2")]
    robots = {"lag": LaggingBackend(), **VARIANTS}
    for variant, robot in robots.items():
        rows.append(row(f"phi1+{variant}", executions("phi1", arguments.points, robot), None, None if variant == "noise" else ROBOT_RATIO_TARGET))
    table = Table(title="Tracking model: held-out prediction of an execution against the plan's", title_justify="left")
    for column in ("case", "executions", "model", "held-out RMS (mm)", "plan RMS (mm)", "ratio", "target", "", "fit"):
        table.add_column(column, justify="left" if column in ("case", "model", "target") else "right")
    for values in rows:
        table.add_row(*values)
    Console(width=150).print(table)


if __name__ == "__main__":
    main()
