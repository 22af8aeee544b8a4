"""Command start-up: the CPU time of whole `stlopt` commands against `python -c "import numpy"`
in the same environment (median of 5), and a whole `stlopt robustness` on a 100,000-sample CSV.

Targets (issue: instant start-up): `stlopt --help` and `stlopt robustness` on a small file at
most 2x the numpy import.
"""

from __future__ import annotations

import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

from benchmarks._timing import Row, print_table

ROOT = Path(__file__).resolve().parent.parent
STLOPT = str(Path(sys.executable).parent / "stlopt")


def cpu_seconds(command: list[str], repeats: int = 5) -> float:
    """Median user + system CPU seconds of a child process running `command`."""
    runs = []
    for _ in range(repeats):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run(command, cwd=ROOT, capture_output=True, check=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        runs.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return statistics.median(runs)


def long_trace(folder: Path, samples: int = 100_000) -> Path:
    """The three-region path stretched to `samples` samples at 100 Hz, as a CSV."""
    from stl_lfd import SignalTable, read_signal_csv, write_signal_csv

    table = read_signal_csv(ROOT / "examples" / "three_regions.csv")
    times = np.arange(samples) / 100.0
    stretched = times * (table.times[-1] / times[-1])
    path = folder / "long.csv"
    write_signal_csv(SignalTable(times, {name: np.interp(stretched, table.times, values) for name, values in table.columns.items()}), path)
    return path


def rows() -> list[Row]:
    numpy_import = cpu_seconds([sys.executable, "-c", "import numpy"])
    result = [Row('python -c "import numpy"', "", numpy_import, note="the yardstick")]
    for name, command in (
        ("stlopt --help", [STLOPT, "--help"]),
        ("stlopt robustness (small file)", [STLOPT, "robustness", "specs/phi1.stl", "examples/three_regions.csv"]),
    ):
        seconds = cpu_seconds(command)
        result.append(Row(name, "CPU time", seconds, 2 * numpy_import, note=f"{seconds / numpy_import:.2f}x numpy"))
    with tempfile.TemporaryDirectory() as folder:
        trace = long_trace(Path(folder))
        command = [STLOPT, "robustness", "specs/phi1.stl", str(trace), "--semantics", "classic"]
        seconds = cpu_seconds(command)
        ours = float(subprocess.run(command, cwd=ROOT, capture_output=True, text=True, check=True).stdout)
        result.append(Row("stlopt robustness, phi1 (whole command)", "100,000 samples", seconds, note=f"{seconds / numpy_import:.2f}x numpy"))
        rtamt = rtamt_row(trace, ours, seconds)
        if rtamt is not None:
            result.append(rtamt)
    return result


def rtamt_phi1() -> str:
    """phi1 in RTAMT's language, regions written out as `half_width - abs(s - centre) > 0`."""
    from stl_lfd.stl import Spec, region_boxes

    boxes = region_boxes(Spec.load(ROOT / "specs" / "phi1.stl").tree)

    def box(name: str) -> str:
        return "(" + " and ".join(f"({(hi - lo) / 2!r} - abs({signal} - {(hi + lo) / 2!r}) > 0)" for signal, (lo, hi) in boxes[name].items()) + ")"

    return f"(eventually {box('L1')}) and (always[12s,17s] {box('L2')}) and (eventually {box('L3')}) and (eventually[8s,12s] {box('L4')})"


def rtamt_row(trace: Path, ours: float, our_seconds: float) -> Row | None:
    """RTAMT 0.4.10 evaluating the same spec in-process (parsing excluded), if installed."""
    try:
        import rtamt
    except ImportError:
        return None
    from stl_lfd import read_signal_csv

    table = read_signal_csv(trace)
    spec = rtamt.StlDiscreteTimeSpecification()
    for name in "xyz":
        spec.declare_var(name, "float")
    spec.set_sampling_period(10, "ms", 0.1)
    spec.spec = rtamt_phi1()
    spec.parse()
    data = {"time": table.times.tolist(), **{name: table.columns[name].tolist() for name in "xyz"}}
    start = resource.getrusage(resource.RUSAGE_SELF)
    value = spec.evaluate(data)[0][1]
    end = resource.getrusage(resource.RUSAGE_SELF)
    seconds = end.ru_utime - start.ru_utime + end.ru_stime - start.ru_stime
    same = "equal" if abs(value - ours) < 1e-9 else f"DIFFERENT: {value!r} vs {ours!r}"
    return Row("RTAMT 0.4.10 in-process, evaluation only", "100,000 samples", seconds, note=f"values {same}; stlopt {seconds / our_seconds:.0f}x faster")


def main() -> None:
    print_table("Command start-up (CPU seconds, median of 5)", rows())


if __name__ == "__main__":
    main()
