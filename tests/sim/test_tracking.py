"""The tracking model: it recovers how a robot follows references (lag, sag, clock), keeps the
plan when the robot executes the plan, and predicts in batches and after a round trip alike."""

import numpy as np
import pytest
from scipy.signal import lfilter

from stl_lfd.sim import Reference, load_scene
from stl_lfd.sim.tracking_model import Execution, PredictingBackend, TrackingModel

RATE = 100.0


def reference(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """12 s of a smooth random path at 240 Hz (`R` times, `R x 3` positions)."""
    generator = np.random.default_rng(seed)
    times = np.arange(0, 12.0 + 1e-9, 1 / 240)
    frequencies, phases = generator.uniform(0.05, 0.3, (3, 3)), generator.uniform(0, 2 * np.pi, (3, 3))
    positions = np.stack([0.4 + 0.1 * np.sin(2 * np.pi * frequencies[axis] * times[:, None] + phases[axis]).sum(axis=1) / 3 for axis in range(3)], axis=1)
    return times, positions


def executed(seed: int, lag: float = 0.0, sag: float = 0.0, clock: float = 1.0) -> Execution:
    """What a robot with a first-order `lag` (s), sitting `sag` below and reading the reference
    on its `clock`, records at RATE."""
    reference_times, positions = reference(seed)
    times = np.arange(0, 12.0 + 1e-9, 1 / RATE)
    target = np.column_stack([np.interp(clock * times, reference_times, positions[:, axis]) for axis in range(3)])
    if lag > 0:
        keep = np.exp(-1 / (RATE * lag))
        target = lfilter([1 - keep], [1, -keep], target - target[0], axis=0) + target[0]
    return Execution(reference_times, positions, times, target + np.array([0.0, 0.0, -sag]))


def test_a_lagging_sagging_robot_is_learned_and_predicted_on_a_path_it_never_saw():
    model = TrackingModel().fit([executed(seed, lag=0.2, sag=0.01) for seed in range(3)])
    unseen = executed(7, lag=0.2, sag=0.01)
    error = model.predict(unseen.reference_times, unseen.reference_positions, unseen.times) - unseen.positions
    plan_error = unseen.reference_positions[:: int(240 / RATE)][: len(unseen.times)] - unseen.positions
    assert model.kind_ in ("filter", "clocked filter")
    assert np.sqrt(np.mean(error**2)) < 0.05 * np.sqrt(np.mean(plan_error**2))
    assert np.all(model.heldout_rms_ < 0.1 * model.plan_rms_)


def test_a_slow_clock_is_found():
    model = TrackingModel().fit([executed(seed, clock=0.8) for seed in range(3)])
    assert model.kind_ == "clocked filter" and model.clock_ == pytest.approx(0.8, abs=0.005)
    assert np.all(model.heldout_rms_ < 1e-4)


def test_a_robot_that_executes_the_plan_keeps_the_plan():
    model = TrackingModel().fit([executed(seed) for seed in range(3)])
    assert model.kind_ == "plan" and model.clock_ == 1.0
    assert np.all(model.heldout_rms_ < 1e-12) and np.all(model.offsets_ == 0)


def test_batches_and_a_round_trip_predict_the_same():
    model = TrackingModel().fit([executed(seed, lag=0.1, sag=0.005, clock=0.9) for seed in range(2)])
    times, _ = reference(0)
    batch = np.stack([reference(seed)[1] for seed in (3, 4)])
    grid = np.arange(0, 12.0, 1 / RATE)
    together = model.predict(times, batch, grid)
    assert together.shape == (2, grid.size, 3)
    assert np.array_equal(together[1], model.predict(times, batch[1], grid))
    restored = TrackingModel.from_dict(model.to_dict())
    assert np.array_equal(restored.predict(times, batch[0], grid), together[0])


def test_the_predicting_backend_records_the_predicted_positions():
    model = TrackingModel().fit([executed(seed, sag=0.02) for seed in range(2)])
    times, positions = reference(5)
    signals = PredictingBackend(model).run(Reference(times, positions), load_scene("free_space"), RATE).signals
    assert signals.columns["z"] == pytest.approx(np.interp(signals.times, times, positions[:, 2]) - 0.02, abs=1e-9)
    assert signals.source == "predicted execution"


def test_fitting_needs_an_execution():
    with pytest.raises(ValueError, match="at least one execution"):
        TrackingModel().fit([])


def test_a_plan_good_enough_is_kept_without_fitting_the_rest():
    almost = [executed(seed, sag=0.0004) for seed in range(2)]
    assert TrackingModel().fit(almost, plan_within=0.001).kind_ == "plan"
    assert TrackingModel().fit(almost).kind_ == "offset"


def test_a_reference_that_never_moves_still_gives_a_model():
    times = np.arange(0, 5, 0.01)
    still = np.tile([0.4, 0.1, 0.4], (len(times), 1))
    model = TrackingModel().fit([Execution(times, still, times, still + [0, 0, -0.01]), Execution(times, still, times, still + [0, 0, -0.012])])
    assert model.predict(times, still, times)[:, 2] == pytest.approx(0.4 - 0.011)


def test_more_parameters_only_where_they_predict_better():
    sagging = [executed(0, sag=0.01)]  # one execution: errors are in-sample, where the bank fits a hair better
    assert TrackingModel().fit(sagging).kind_ == "offset"
    assert TrackingModel().fit([executed(0, lag=0.2)]).kind_ in ("filter", "clocked filter")


def test_a_slow_robot_grasps_later_and_holds_its_gripper_on_its_clock():
    times, positions = reference(2)
    gripper = np.where(times < 3.0, 0.08, 0.0)
    slow = TrackingModel(kind_="clocked filter", clock_=0.5)
    predicted = PredictingBackend(slow).predicted(Reference(times, positions, gripper=gripper, events=((3.0, "grasp"), (9.0, "release"))), RATE)
    assert predicted.events == ((6.0, "grasp"),)  # the release comes after the recording ends
    assert predicted.gripper[predicted.times < 5.9] == pytest.approx(0.08) and predicted.gripper[predicted.times > 6.1] == pytest.approx(0.0)
    assert predicted.positions[-1] == pytest.approx(positions[np.searchsorted(times, 6.0)], abs=1e-3)
