"""The numbers a spec compares single signals with, for the report to draw."""

from stl_lfd.stl import parse
from stl_lfd.stl.thresholds import signal_thresholds


def test_thresholds_are_read_through_definitions_with_the_signal_on_the_left():
    spec = parse("NEAR := x in [0, 1]\nSLOW := G speed < 0.5\nmine := F NEAR & SLOW & 2.0 > force & G (force < 2 -> abs(x - y) < 1) & F depth >= 0.01\n")
    found = {signal: [str(threshold) for threshold in thresholds] for signal, thresholds in signal_thresholds(spec).items()}
    assert found == {"speed": ["speed < 0.5"], "force": ["force < 2"], "depth": ["depth >= 0.01"]}


def test_an_unused_definition_brings_no_threshold():
    spec = parse("UNUSED := tilt < 0.1\nmine := F z > 0.3\n")
    assert list(signal_thresholds(spec)) == ["z"]
