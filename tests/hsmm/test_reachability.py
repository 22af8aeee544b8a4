"""The bundled demonstrations are designed so that the paper's adaptation is possible: moving
the means of states 2-3 within +-2 standard deviations and the duration means within +-1
standard deviation (plus, for phi2, the reduced transition band) satisfies phi1 and phi2,
while the learned skill violates both.

The points below are positions inside the bounds of `configs/phi1.yaml` and `configs/phi2.yaml`
(0 = lower bound, 1 = upper bound, per parameter), found by `stlopt optimize` (method stl; phi1
on the kinematic backend, phi2 with PyBullet). These tests pin that such points exist and stay
valid as the model code changes.
"""

import numpy as np
import pytest

from stl_lfd.hsmm import retrieve
from stl_lfd.optim import build_search_space, load_task
from stl_lfd.stl import compile_spec, load_spec
from tests.conftest import ROOT

POINTS = {
    "phi1": [0.3523, 0.1106, 0.5819, 1.0, 0.6072, 0.0955, 0.8, 1.0, 0.202, 0.5576, 0.0, 0.4233],
    "phi2": [
        0.714,
        0.3959,
        0.4177,
        0.5545,
        0.0949,
        0.8323,
        0.9213,
        0.9611,
        0.8278,
        0.8526,
        0.5979,
        0.5906,
        1.0,
        0.6694,
        0.4909,
        0.0889,
        0.3643,
        0.3993,
        0.3053,
        0.213,
        0.6598,
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
