"""The STL robustness, skill learning and the command's start on two commits, timed in turns:
is a refactoring slower?

    python -m benchmarks.bench_commits OLD [NEW] [--rounds 5]

Each commit is checked out in a temporary git worktree; a fresh Python process per commit and
round times every workload (the median of several calls, after a warm-up) with that commit's
`stl_lfd` first on its path, the two commits alternating round after round, so that both see
the same machine. A workload's time on a commit is its smallest over the rounds (the least
disturbed one); the table gives both and NEW / OLD. NEW defaults to the working tree.

The workloads: the paper's specs, untils, windows and nested operators in both semantics on
the 22 s three-region trace and on bench_stl's oscillating trace (what the optimiser evaluates
after every rollout); learning the three-region skill (6 states) and retrieving its reference;
and `import stl_lfd.cli`, what every `stlopt` command pays first.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

from benchmarks._timing import Row, format_seconds, print_table

ROOT = Path(__file__).resolve().parent.parent

WORKLOADS = (
    ("phi1", "spec:phi1"),
    ("phi2", "spec:phi2"),
    ("until", "(x > 0.4) U (y > 0.15)"),
    ("bounded until", "(x > 0.4) U[0,5] (y > 0.15)"),
    ("G over until", "G[0,5] (x > 0.4) U (y > 0.1)"),
    ("windows", "G[0,3] F[0,2] (x > 0.45)"),
    ("oscillating until", "osc:(x > 0.42) U (y > 0.12)"),
    ("oscillating F over until", "osc:F[2,9] ((y < 0.1) U[0,3] (x > 0.48))"),
)

# Runs inside each commit's worktree: prints {case: seconds} as JSON.
TIMER = """
import json, statistics, sys, time
import numpy as np
from stl_lfd import read_signal_csv
from stl_lfd.stl import compile_spec, load_spec, parse

root, workloads = sys.argv[1], json.loads(sys.argv[2])
table = read_signal_csv(root + "/examples/three_regions.csv")
times = np.arange(2200) / 100
trace = {name: np.interp(times, table.times, values) for name, values in table.columns.items()}
oscillating = {"x": 0.45 + 0.1 * np.sin(times / 3), "y": 0.2 * np.cos(times / 2 + 0.3), "z": 0.4 + 0 * times}
result = {}
for case, text in workloads:
    signals = oscillating if text.startswith("osc:") else trace
    text = text.removeprefix("osc:")
    for semantics in ("classic", "new"):
        spec = load_spec(root + "/specs/" + text[5:] + ".stl") if text.startswith("spec:") else parse(text)
        function = compile_spec(spec, semantics)
        function(signals, times)
        runs = []
        for _ in range(7):
            start = time.perf_counter()
            for _ in range(5):
                function(signals, times)
            runs.append((time.perf_counter() - start) / 5)
        result[case + ", " + semantics] = statistics.median(runs)
from stl_lfd import learn_from_folder, retrieve
start = time.perf_counter()
model = learn_from_folder(root + "/demos/three_regions", 6)[0]
result["learn three_regions, 6 states"] = time.perf_counter() - start
retrieve(model)
runs = []
for _ in range(5):
    start = time.perf_counter()
    retrieve(model)
    runs.append(time.perf_counter() - start)
result["retrieve its reference"] = statistics.median(runs)
print(json.dumps(result))
"""


STARTUP = "import json, time; start = time.perf_counter(); import stl_lfd.cli; print(json.dumps({'import stl_lfd.cli': time.perf_counter() - start}))"


def timings(worktree: Path) -> dict[str, float]:
    """One round of every workload in fresh processes on `worktree`'s code."""
    result = {}
    for script, arguments in ((TIMER, [str(worktree), json.dumps(WORKLOADS)]), (STARTUP, [])):
        completed = subprocess.run(
            [sys.executable, "-c", script, *arguments],
            cwd=worktree,
            env={"PYTHONPATH": str(worktree), "PATH": "/usr/bin:/bin", "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"},
            capture_output=True,
            text=True,
        )
        if completed.returncode != 0:
            raise SystemExit(f"{worktree}: the timing process failed:\n{completed.stderr}")
        result |= json.loads(completed.stdout)
    return result


def compare(old: str, new: str | None, rounds: int) -> list[Row]:
    with tempfile.TemporaryDirectory() as folder:
        trees = []
        for name, commit in (("old", old), ("new", new)):
            if commit is None:
                trees.append(ROOT)
                continue
            tree = Path(folder) / name
            subprocess.run(["git", "worktree", "add", "--detach", str(tree), commit], cwd=ROOT, check=True, capture_output=True)
            trees.append(tree)
        try:
            best: list[dict[str, float]] = [{}, {}]
            for _ in range(rounds):
                for index, tree in enumerate(trees):
                    for case, seconds in timings(tree).items():
                        best[index][case] = min(seconds, best[index].get(case, seconds))
        finally:
            for tree in trees:
                if tree != ROOT:
                    subprocess.run(["git", "worktree", "remove", "--force", str(tree)], cwd=ROOT, capture_output=True)
    return [Row(case, f"old {format_seconds(best[0][case])}", best[1][case], note=f"new/old {best[1][case] / best[0][case]:.2f}") for case in best[0]]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("old", help="the commit to compare against")
    parser.add_argument("new", nargs="?", default=None, help="the commit to compare (default: the working tree)")
    parser.add_argument("--rounds", type=int, default=5)
    arguments = parser.parse_args()
    print_table(
        f"{arguments.new or 'working tree'} against {arguments.old} (best of {arguments.rounds} rounds each, in turns)",
        compare(arguments.old, arguments.new, arguments.rounds),
    )


if __name__ == "__main__":
    main()
