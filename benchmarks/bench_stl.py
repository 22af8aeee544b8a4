"""STL robustness: the paper's specs on a 20 s trace at 240 Hz, batches, and scaling in trace
length and window width."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from benchmarks._timing import Row, median_seconds, print_table
from stl_lfd.stl import compile_spec, load_spec, parse

ROOT = Path(__file__).resolve().parent.parent
RATE_HZ = 240


def three_region_trace(samples: int = 20 * RATE_HZ) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """A smooth path through the free-space regions, as a rollout would record it."""
    from stl_lfd.signals import read_signal_csv

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


def main() -> None:
    print_table("STL robustness: the paper's specifications", spec_rows())
    print_table("STL robustness: scaling (classic cost linear in length, flat in window width)", scaling_rows())


if __name__ == "__main__":
    main()
