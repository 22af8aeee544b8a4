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


def test_thresholds_on_expressions_of_signals_are_read_with_their_values():
    import numpy as np

    from stl_lfd.stl.thresholds import expression_thresholds, expression_values

    spec = parse("ON := abs(box_x - shelf_x) < 0.01 & 0.005 > abs(box_z - shelf_z - 0.03)\nmine := F G ON & G force < 5 & F x > 0.2\n")
    found = expression_thresholds(spec)
    assert [str(threshold) for thresholds in found.values() for threshold in thresholds] == [
        "abs(box_x - shelf_x) < 0.01",
        "abs(box_z - shelf_z - 0.03) < 0.005",
    ]
    columns = {"box_x": np.array([0.5, 0.52]), "shelf_x": np.array([0.51, 0.51]), "box_z": np.zeros(2), "shelf_z": np.zeros(2)}
    assert np.allclose(expression_values(found["abs(box_x - shelf_x)"][0].expression, columns), [0.01, 0.01])
    assert np.allclose(expression_values(found["abs(box_z - shelf_z - 0.03)"][0].expression, columns), [0.03, 0.03])
