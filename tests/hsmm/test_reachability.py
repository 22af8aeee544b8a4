"""The bundled demonstrations are designed so that the paper's adaptation is possible: moving
the means of states 2-3 within +-2 standard deviations and the duration means within +-1
standard deviation (plus, for phi2, the reduced transition band) satisfies phi1 and phi2,
while the learned skill violates both.

The points below are positions inside the bounds of `configs/phi1.yaml` and `configs/phi2.yaml`
(0 = lower bound, 1 = upper bound, per parameter), found by `stlopt optimize` on the kinematic
backend. These tests pin that such points exist and stay valid as the model code changes.
"""

import numpy as np
import pytest

from stl_lfd.hsmm import retrieve
from stl_lfd.optim import build_search_space, load_task
from stl_lfd.stl import compile_spec, load_spec
from tests.conftest import ROOT

POINTS = {
    "phi1": [0.005, 0.8484, 0.7445, 0.9914, 0.5767, 0.1848, 0.4697, 0.718, 0.2223, 0.4764, 0.2989, 0.6976],
    "phi2": [
        0.1386, 1.0, 0.6538, 1.0, 0.6111, 0.1362, 0.3278, 1.0, 0.0, 0.0016, 0.0,
        0.4588, 0.7641, 0.2479, 0.037, 0.0, 0.3746, 0.487, 0.1172, 0.6345, 0.2646,
    ],
}


def robustness(model, spec: str, semantics: str) -> float:
    trajectory = retrieve(model, duration=22, rate=100)
    function = compile_spec(load_spec(ROOT / "specs" / f"{spec}.stl"), semantics)
    return function(dict(zip("xyz", trajectory.positions.T)), trajectory.times)


@pytest.mark.parametrize("spec", ["phi1", "phi2"])
@pytest.mark.parametrize("semantics", ["classic", "new"])
def test_the_learned_skill_violates_the_spec(learned_model, spec, semantics):
    assert robustness(learned_model, spec, semantics) < -0.01


@pytest.mark.parametrize("spec", ["phi1", "phi2"])
@pytest.mark.parametrize("semantics", ["classic", "new"])
def test_the_spec_is_satisfiable_within_the_bounds(learned_model, spec, semantics):
    space = build_search_space({"skill": learned_model}, load_task(ROOT / "configs" / f"{spec}.yaml").parameters)
    unit = np.array(POINTS[spec])
    assert unit.shape == (space.dimension,) and np.all((unit >= 0) & (unit <= 1))
    adapted = space.apply({"skill": learned_model}, space.lower + unit * (space.upper - space.lower))["skill"]
    assert robustness(adapted, spec, semantics) > 0.01
