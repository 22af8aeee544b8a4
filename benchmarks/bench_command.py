"""The command backend against the in-process PyBullet backend: phi1, the same seed, each trial
executed by `examples/pybullet_executor.py` in its own process. The trials must be identical;
the table shows the wall time per trial and the executor's overhead per trial.

    python -m benchmarks.bench_command [--trials 32]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

from benchmarks._timing import Row, print_table
from benchmarks.bench_ray import same_trials
from stl_lfd.optim import RunDirectory, Trial, finish_run, load_task, start_run
from stl_lfd.sim import Command

ROOT = Path(__file__).resolve().parent.parent
EXECUTOR = ROOT / "examples" / "pybullet_executor.py"


def timed_run(task, folder: Path) -> tuple[float, list[Trial]]:
    start = time.perf_counter()
    finish_run(start_run(task, folder))
    seconds = time.perf_counter() - start
    return seconds, RunDirectory(folder).trials()


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=8, help="trials per run (the acceptance uses 32)")
    arguments = parser.parse_args(argv)
    task = load_task(ROOT / "configs" / "phi1.yaml").with_overrides(trials=arguments.trials, initial=min(8, arguments.trials))
    command = task.with_overrides(backend="command", command=Command.parse([sys.executable, str(EXECUTOR), "{reference}", "{signals}"], cwd=ROOT))
    with tempfile.TemporaryDirectory() as folder:
        in_process, in_process_trials = timed_run(task, Path(folder) / "pybullet")
        external, external_trials = timed_run(command, Path(folder) / "command")
    same = same_trials(in_process_trials, external_trials)
    executions = arguments.trials + 1  # the unoptimised skill is executed too
    overhead = (external - in_process) / executions
    print_table(
        f"Command backend (phi1, {arguments.trials} trials, seed 0; trials identical to in-process: {'yes' if same else 'NO'})",
        [
            Row("pybullet, in process", f"{executions} executions", in_process / executions, None, f"{in_process:.1f} s for the run"),
            Row("command: pybullet executor", f"{executions} executions", external / executions, None, f"{external:.1f} s for the run"),
            Row("executor overhead", "per execution", overhead, None, f"{external / in_process:.2f}x the in-process run"),
        ],
    )
    if not same:
        sys.exit("the command backend gave other trials than the in-process backend")


if __name__ == "__main__":
    main()
