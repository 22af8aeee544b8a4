"""The new robustness's cost warning: an estimate in seconds, once per compiled spec."""

import warnings

import numpy as np

import stl_lfd.stl.robustness as robustness
from stl_lfd.stl import CostWarning, compile_spec


def test_a_costly_evaluation_is_announced_once_in_seconds(monkeypatch):
    spec = compile_spec("F[0, 2] x > 0.5", "new")
    times = np.linspace(0.0, 10.0, 1001)
    batch = {"x": np.tile(np.sin(times), (8, 1))}
    # 8 traces x 1001 samples x 201 window samples = 1.6e6 operations: 0.03 s at 5e7 per second
    monkeypatch.setattr(robustness, "COSTLY_SECONDS", 0.01)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        spec(batch, times)
        spec(batch, times)
    costs = [str(warning.message) for warning in caught if issubclass(warning.category, CostWarning)]
    assert len(costs) == 1
    assert "on 8 traces of 1001 samples takes about 0 s on one core (windows of up to 201 samples" in costs[0]


def test_the_bundled_tasks_evaluations_are_not_announced():
    spec = compile_spec("F[0, 20] x > 0.5 & G (y > 0 -> z < 2)", "new")
    times = np.linspace(0.0, 36.0, 3601)
    with warnings.catch_warnings():
        warnings.simplefilter("error", CostWarning)
        spec({"x": np.tile(times, (64, 1)), "y": np.tile(times, (64, 1)), "z": np.tile(times, (64, 1))}, times)
