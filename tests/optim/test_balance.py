"""The parts of a spec on one scale for the search (`methods/balance.py`): the units a predicate
is written in do not change what methods plan and stl propose, and never the verdict."""

import dataclasses
import tempfile
import warnings
from pathlib import Path

import numpy as np
import pytest

from stl_lfd.optim.methods.balance import balanced_values, output_scales
from stl_lfd.stl import Semantics
from tests.conftest import ROOT


def test_a_scale_follows_the_units_of_its_column():
    rng = np.random.default_rng(0)
    values = rng.normal(size=(8, 3))
    in_millimetres = values * np.array([1.0, 1000.0, 1.0])
    assert np.allclose(output_scales(in_millimetres), output_scales(values) * np.array([1.0, 1000.0, 1.0]))


def test_one_trial_that_pushed_hard_does_not_set_the_scale():
    forces = np.array([[-1.0], [-1.2], [-0.8], [-1.1], [-0.9], [-95.0]])
    assert output_scales(forces)[0] < 1.0


def test_a_column_that_never_varies_or_is_unknown_still_has_a_positive_scale():
    values = np.array([[0.5, 0.0, np.nan], [0.5, 0.0, np.nan]])
    assert output_scales(values).tolist() == [0.5, 1.0, 1.0]


def test_fewer_trials_than_show_a_spread_leave_the_parts_as_recorded():
    from stl_lfd.optim.methods.stl import PartsData

    two = PartsData(np.array([[0.0001, -3.0], [0.0002, -2.0]]), np.empty((2, 0)), Semantics("classic"))
    assert (
        two.balanced().scales is None and PartsData(np.vstack([two.parts, [[0.0, -1.0]]]), np.empty((3, 0)), Semantics("classic")).balanced().scales is not None
    )


@pytest.mark.parametrize("semantics", [Semantics("classic"), Semantics("new", 1.0)])
def test_balancing_keeps_the_sign_of_the_composed_robustness(semantics):
    rng = np.random.default_rng(1)
    outputs = rng.normal(size=(200, 3)) * np.array([0.01, 20.0, 1.0])
    unscaled = balanced_values(outputs, np.ones(3), 3, (), semantics)
    balanced = balanced_values(outputs, output_scales(outputs), 3, (), semantics)
    assert np.array_equal(np.sign(unscaled), np.sign(balanced)) and not np.allclose(unscaled, balanced)


REGIONS = (ROOT / "specs" / "regions.stl").as_posix()
IN_METRES = f'include "{REGIONS}"\nphi := F L1 & G[12, 17] L2 & F L3 & F[8, 12] L4\n'
IN_MILLIMETRES = (
    f'include "{REGIONS}"\n'
    "L4mm := 1000 * x in [460, 560] & 1000 * y in [100, 200] & 1000 * z in [350, 450]\n"
    "phi := F L1 & G[12, 17] L2 & F L3 & F[8, 12] L4mm\n"
)


def proposed_points(spec_text: str, method: str, balance: bool, folder: Path) -> list[np.ndarray]:
    from stl_lfd.optim import RunDirectory, finish_run, load_task, start_run
    from stl_lfd.optim.methods.tuning import CompositeSettings, PlanSettings

    spec = folder / f"spec-{len(list(folder.iterdir()))}.stl"
    spec.write_text(spec_text)
    task = load_task(ROOT / "benchmarks" / "problems" / "phi1_first.yaml").with_overrides(spec=spec, method=method, initial=4, trials=8, seed=3)
    settings = PlanSettings(balance=balance) if method == "plan" else CompositeSettings(balance=balance)
    task = dataclasses.replace(task, optimizer=dataclasses.replace(task.optimizer, tuning={method: settings}))
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as run:
        with start_run(task, Path(run) / "run") as prepared:
            finish_run(prepared)
        return [trial.x for trial in RunDirectory(Path(run) / "run").trials()]


@pytest.mark.slow
def test_method_plan_proposes_the_same_points_whether_a_region_is_in_metres_or_millimetres(tmp_path):
    metres, millimetres = (proposed_points(text, "plan", True, tmp_path) for text in (IN_METRES, IN_MILLIMETRES))
    assert np.allclose(metres, millimetres, rtol=0, atol=1e-9)
    unbalanced = proposed_points(IN_MILLIMETRES, "plan", False, tmp_path)
    assert not np.allclose(metres, unbalanced, rtol=0, atol=1e-3)  # as recorded, the millimetres steer it


@pytest.mark.slow
def test_method_stl_proposes_the_same_first_model_point_in_metres_or_millimetres(tmp_path):
    metres, millimetres = (proposed_points(text, "stl", True, tmp_path) for text in (IN_METRES, IN_MILLIMETRES))
    assert np.allclose(metres[:5], millimetres[:5], rtol=0, atol=1e-6)  # the Sobol design, then the model's first
    unbalanced = proposed_points(IN_MILLIMETRES, "stl", False, tmp_path)
    assert not np.allclose(metres[4], unbalanced[4], rtol=0, atol=1e-3)
