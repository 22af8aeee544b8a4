"""STL robustness: the paper's specs on a 20 s trace at 240 Hz, batches, scaling in trace
length and window width, and specifications of megabytes (flat conjunctions, many definitions,
nesting at the limit)."""

from __future__ import annotations

import random
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from benchmarks._timing import Row, format_seconds, median_seconds, paired_median_seconds, print_table
from stl_lfd.stl import MAX_DEPTH, HorizonWarning, compile_spec, evaluate_file, load_spec, parse

ROOT = Path(__file__).resolve().parent.parent
RATE_HZ = 240


def three_region_trace(samples: int = 20 * RATE_HZ) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """A smooth path through the free-space regions, as a rollout would record it."""
    from stl_lfd import read_signal_csv

    table = read_signal_csv(ROOT / "examples" / "three_regions.csv")
    times = np.arange(samples) / RATE_HZ
    return {name: np.interp(times, table.times, values) for name, values in table.columns.items()}, times


def spec_rows() -> list[Row]:
    signals, times = three_region_trace()
    rows = []
    for name in ("phi1", "phi2"):
        spec = load_spec(ROOT / "specs" / f"{name}.stl")
        for semantics, target in (("classic", 1e-3), ("new", 10e-3)):
            function = compile_spec(spec, semantics)
            seconds = median_seconds(lambda: function(signals, times), number=20)
            rows.append(Row(f"{name} {semantics}", "4,800 samples x 3", seconds, target))
    rng = np.random.default_rng(0)
    batch = {name: values + rng.normal(0, 0.005, size=(1000, values.size)) for name, values in signals.items()}
    function = compile_spec(load_spec(ROOT / "specs" / "phi1.stl"), "classic")
    rows.append(Row("phi1 classic, batch", "1,000 x 4,800 x 3", median_seconds(lambda: function(batch, times), repeats=3), 1.0))
    return rows


def scaling_rows() -> list[Row]:
    """Classic `G F[0, w] x > 0`: inner F at every sample, so cost follows trace length only."""
    rng = np.random.default_rng(1)
    rows = []
    width_seconds = 1.0
    for samples in (10_000, 100_000, 1_000_000):
        signals, times = {"x": rng.normal(size=samples)}, np.arange(samples) / RATE_HZ
        function = compile_spec(parse(f"G F[0, {width_seconds}] x > 0"), "classic")
        seconds = median_seconds(lambda: function(signals, times), repeats=5)
        rows.append(Row("G F[0,1 s] x > 0", f"{samples:,} samples", seconds, note=f"{seconds / samples * 1e9:.1f} ns/sample"))
    samples = 100_000
    signals, times = {"x": rng.normal(size=samples)}, np.arange(samples) / RATE_HZ
    for width in (10, 100, 1_000, 10_000):
        function = compile_spec(parse(f"G F[0, {width / RATE_HZ}] x > 0"), "classic")
        seconds = median_seconds(lambda: function(signals, times), repeats=5)
        rows.append(Row("G F[0,w] x > 0", f"{samples:,} samples, w = {width:,}", seconds))
    signals, times = {"x": rng.normal(size=1000), "y": rng.normal(size=1000)}, np.arange(1000.0)
    for semantics in ("classic", "new"):
        function = compile_spec(parse("x > 0 U[0, 100] y > 0"), semantics)
        seconds = median_seconds(lambda: function.trace(signals, times), repeats=3)
        rows.append(Row(f"until[0,100] {semantics}, every sample", "1,000 samples", seconds))
    return rows


UNTIL_FORMULAS = (
    "(x > 0.4) U (y > 0.15)",
    "(x > 0.4) U[0,5] (y > 0.15)",
    "G[0,5] (x > 0.4) U (y > 0.1)",
    "G[0,4] ((z > 0.39) U (x > 0.5))",
    "F[0,3] ((z > 0.39) U (x > 0.5))",
)
# The new robustness of an until may cost at most this many times the classic one.
UNTIL_RATIO_TARGET = 20


def paired_seconds(text: str, signals: dict[str, np.ndarray], times: np.ndarray, repeats: int = 9, numbers: tuple[int, int] = (20, 1)) -> tuple[float, float]:
    """Seconds of the classic and of the new robustness of `text` on one trace, timed in turns."""
    classic, new = (compile_spec(parse(text), semantics) for semantics in ("classic", "new"))
    return paired_median_seconds(lambda: classic(signals, times), lambda: new(signals, times), repeats=repeats, numbers=numbers)


def ratio_row(case: str, text: str, signals: dict[str, np.ndarray], times: np.ndarray, note: str = "") -> Row:
    """A row of the new robustness's time on one trace, its target UNTIL_RATIO_TARGET times the classic's."""
    classic_seconds, new_seconds = paired_seconds(text, signals, times)
    note += f"classic {format_seconds(classic_seconds)}, new/classic {new_seconds / classic_seconds:.0f}x"
    return Row(case, f"{times.size:,} samples", new_seconds, UNTIL_RATIO_TARGET * classic_seconds, note)


def until_rows() -> list[Row]:
    """Until under the new robustness against the classic one, on the same 22 s trace at 100 Hz,
    both timed in this run: the time column is the new robustness, the target 20x the classic."""
    from stl_lfd import read_signal_csv

    table = read_signal_csv(ROOT / "examples" / "three_regions.csv")
    times = np.arange(2200) / 100
    signals = {name: np.interp(times, table.times, values) for name, values in table.columns.items()}
    rows = [ratio_row(f"{text}, new", text, signals, times) for text in UNTIL_FORMULAS]
    return rows


# A seeded family of traces nobody tuned the kernels on, and formulas over them.
RANDOM_TRACES = 6  # per kind (smooth, noisy)
RANDOM_UNTILS = ("(x > {a}) U (y > {b})", "(x > {a}) U[0,5] (y > {b})", "F[2,9] ((y < {b}) U[0,3] (x > {a}))")
RANDOM_WINDOWS = ("G[0,5] (x > {a})", "F[0,8] (y < {b})", "G[0,3] F[0,2] (x > {a})")
REFERENCE_SAMPLES = 200  # the reference evaluates one sample at a time: agreement is checked on a prefix
# A smooth oscillating trace on which the until's kernel once took hundreds of times the classic.
OSCILLATING_FORMULAS = ("(x > 0.42) U (y > 0.12)", "F[2,9] ((y < 0.1) U[0,3] (x > 0.48))")


def oscillating_trace(samples: int = 2200) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """x = 0.45 + 0.1 sin(t / 3), y = 0.2 cos(t / 2 + 0.3), 22 s at 100 Hz."""
    times = np.arange(samples) / 100.0
    return {"x": 0.45 + 0.1 * np.sin(times / 3), "y": 0.2 * np.cos(times / 2 + 0.3)}, times


def random_trace(kind: str, seed: int, samples: int = 2200, rate: float = 100.0) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """`smooth`: sums of three sinusoids of random periods (2-20 s), amplitudes and phases per
    signal; `noisy`: a random walk plus white noise. Seeded; 22 s at 100 Hz by default."""
    rng = np.random.default_rng([0 if kind == "smooth" else 1, seed])
    times = np.arange(samples) / rate
    signals = {}
    for name in ("x", "y"):
        if kind == "smooth":
            periods, amplitudes, phases = rng.uniform(2, 20, 3), rng.uniform(0.02, 0.15, 3), rng.uniform(0, 2 * np.pi, 3)
            values = rng.uniform(0.1, 0.5) + sum(a * np.sin(2 * np.pi * times / p + f) for a, p, f in zip(amplitudes, periods, phases))
        else:
            values = rng.uniform(0.1, 0.5) + np.cumsum(rng.normal(0, 0.004, samples)) + rng.normal(0, 0.01, samples)
        signals[name] = values
    return signals, times


def random_formula(template: str, signals: dict[str, np.ndarray], seed: int) -> str:
    """`template` with thresholds between the 30th and 70th percentile of x (a) and y (b), so
    that the formula is neither trivially true nor trivially false."""
    rng = np.random.default_rng(seed)
    a, b = (float(np.quantile(signals[name], rng.uniform(0.3, 0.7))) for name in ("x", "y"))
    return template.format(a=f"{a:.4f}", b=f"{b:.4f}")


def random_trace_rows() -> list[Row]:
    """The new robustness against the classic one on every trace of the family and every
    formula, both timed in this run (paired): per formula shape, the worst ratio; and the
    largest difference from the reference implementation on each trace's first samples."""
    signals, times = oscillating_trace()
    rows = [ratio_row(f"until: {text}", text, signals, times, "oscillating trace; ") for text in OSCILLATING_FORMULAS]
    for family, templates in (("until", RANDOM_UNTILS), ("windows", RANDOM_WINDOWS)):
        for template in templates:
            worst, worst_case, disagreement = 0.0, None, 0.0
            for kind in ("smooth", "noisy"):
                for seed in range(RANDOM_TRACES):
                    signals, times = random_trace(kind, seed)
                    text = random_formula(template, signals, seed)
                    classic_seconds, new_seconds = paired_seconds(text, signals, times, repeats=3, numbers=(10, 1))
                    if new_seconds / classic_seconds > worst:
                        worst, worst_case = new_seconds / classic_seconds, (kind, seed, classic_seconds, new_seconds)
                    disagreement = max(disagreement, reference_difference(text, signals, times))
            kind, seed, classic_seconds, new_seconds = worst_case
            note = f"worst of {2 * RANDOM_TRACES} traces: {kind} seed {seed}, new/classic {worst:.0f}x; reference within {disagreement:.0e}"
            rows.append(Row(f"{family}: {template.format(a='a', b='b')}", "2,200 samples", new_seconds, UNTIL_RATIO_TARGET * classic_seconds, note))
    return rows


def reference_difference(text: str, signals: dict[str, np.ndarray], times: np.ndarray) -> float:
    """The new robustness's relative difference from the reference implementation's, on the
    trace's first REFERENCE_SAMPLES samples (the reference evaluates one sample at a time)."""
    from stl_lfd.stl import definitions

    spec = parse(text)
    prefix, short = {name: values[:REFERENCE_SAMPLES] for name, values in signals.items()}, times[:REFERENCE_SAMPLES]
    expected = definitions.new(spec.formula, prefix, short, 0, 1.0)
    with warnings.catch_warnings():  # the prefix is shorter than the formula's windows: clipped, as the reference clips them
        warnings.simplefilter("ignore", HorizonWarning)
        actual = compile_spec(spec, "new")(prefix, short)
    return abs(actual - expected) / max(1.0, abs(expected))


def conjunction_text(count: int) -> str:
    """`s > 0.5 & s > 1.5 & ...`: about 15 bytes a predicate."""
    return " & ".join(f"s > {i}.5" for i in range(count)) + "\n"


def definitions_text(count: int) -> str:
    """`dN := dM | s > K` with M drawn among the earlier definitions (seeded), the last one the
    specification: about 25 bytes a definition."""
    rng = random.Random(0)
    lines = ["d0 := s > 0"] + [f"d{i} := d{rng.randrange(i)} | s > {i % 97}" for i in range(1, count)]
    return "\n".join(lines) + "\n"


def nested_text(count: int) -> str:
    """`count` formulas `G[0, 0.01] G[0, 0.01] ... (s > 0 & (s > 0 & ...))` nested to the limit, in
    one conjunction."""
    levels = (MAX_DEPTH - 3) // 2
    formula = "G[0, 0.01] " * levels + "(s > 0 & " * levels + "s > 1" + ")" * levels
    return " & ".join([f"({formula})"] * count) + "\n"


def size_rows() -> list[Row]:
    """`stlopt robustness` without the process start (`evaluate_file`: read, parse, check,
    inline, compile, evaluate) on generated specifications, each timed once. The note gives
    seconds per megabyte and its ratio to the same shape at a tenth of the size: 1.0 is linear."""
    signal = Path(__file__).resolve().parent.parent / "examples" / "s1.csv"
    cases = [
        ("conjunction of predicates", conjunction_text, 34_000, "predicates"),
        ("definitions using earlier ones", definitions_text, 12_000, "definitions"),
        (f"nesting at the limit ({MAX_DEPTH} levels)", nested_text, 60, "formulas"),
    ]
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for name, make, small, unit in cases:
            per_megabyte = []
            for count in (small, 10 * small):
                path = Path(folder) / "spec.stl"
                path.write_text(make(count))
                megabytes = path.stat().st_size / 1e6
                start = time.perf_counter()
                evaluate_file(path, signal, "classic")
                seconds = time.perf_counter() - start
                per_megabyte.append(seconds / megabytes)
            note = f"{per_megabyte[1]:.2f} s/MB, {per_megabyte[1] / per_megabyte[0]:.2f}x the s/MB at {megabytes / 10:.2f} MB"
            rows.append(Row(name, f"{10 * small:,} {unit}, {megabytes:.1f} MB", seconds, note=note))
    return rows


def main() -> None:
    print_table("STL robustness: the paper's specifications", spec_rows())
    print_table("STL robustness: scaling (classic cost linear in length, flat in window width)", scaling_rows())
    print_table(f"STL until: the new robustness within {UNTIL_RATIO_TARGET}x the classic on the same trace", until_rows())
    print_table(f"STL on random traces: the new robustness within {UNTIL_RATIO_TARGET}x the classic (worst trace per formula)", random_trace_rows())
    print_table("STL specifications of megabytes: parse and evaluate in time linear in their size", size_rows())


if __name__ == "__main__":
    main()
