"""Both backends on the learned skill: tracking, determinism, recorded signals, bad input."""

import warnings

import numpy as np
import pytest

from stl_lfd.errors import ExecutionError
from stl_lfd.sim import Reference, TrackingWarning, execute, load_scene, new_backend
from stl_lfd.skill.execution import reference_of, rollout_model

SCENE = load_scene("free_space")


@pytest.fixture(scope="module")
def reference(learned_model):
    return reference_of(learned_model, duration=20.0)


@pytest.fixture(scope="module")
def pybullet_rollout(reference):
    return execute(reference, SCENE, "pybullet", rate=100.0)


@pytest.mark.slow
def test_pybullet_tracks_the_retrieved_skill_within_5_mm(pybullet_rollout):
    assert pybullet_rollout.tracking_rms < 0.005
    assert pybullet_rollout.tracking_max < SCENE.tracking_tolerance


@pytest.mark.slow
def test_recorded_signals_follow_the_signal_format(pybullet_rollout):
    signals = pybullet_rollout.signals
    assert list(signals.columns) == ["x", "y", "z", "gripper", "force", "qx", "qy", "qz", "qw", "tilt"]
    assert np.degrees(signals.columns["tilt"]).max() < 1.0  # the hand points down, as the reference asks
    assert signals.samples == 2001 and signals.times[-1] == pytest.approx(20.0)
    assert np.allclose(signals.columns["gripper"], SCENE.gripper_opening, atol=1e-3)
    assert np.all(signals.columns["force"] == 0.0)  # nothing is touched in free space


@pytest.mark.slow
def test_the_same_reference_gives_identical_signals(reference, pybullet_rollout):
    again = execute(reference, SCENE, "pybullet", rate=100.0)
    for name, values in pybullet_rollout.signals.columns.items():
        assert np.array_equal(values, again.signals.columns[name]), name


def test_kinematic_backend_records_the_reference(reference):
    rollout = execute(reference, SCENE, "kinematic", rate=50.0)
    times = rollout.signals.times
    assert times.size == 1001
    assert np.allclose(rollout.signals.columns["x"], np.interp(times, reference.times, reference.positions[:, 0]))
    assert rollout.tracking_max == 0.0


@pytest.mark.slow
def test_unreachable_targets_warn_with_the_worst_error(reference):
    far = Reference(reference.times, reference.positions + np.array([0.6, 0.0, 0.0]))
    with pytest.warns(TrackingWarning, match=r"worst tracking error \d+\.\d mm at t = .* outside the workspace"):
        rollout = execute(far, SCENE, "pybullet")
    assert rollout.tracking_max > 0.1


def test_pushing_into_the_floor_is_measured_as_force():
    times = np.linspace(0.0, 2.0, 481)
    depth = np.clip(times - 0.5, 0.0, 1.0) * 0.5  # from 0.3 m above the floor to 0.2 m below it
    positions = np.column_stack([np.full_like(times, 0.5), np.zeros_like(times), 0.3 - depth])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TrackingWarning)
        rollout = execute(Reference(times, positions), SCENE, "pybullet")
    force = rollout.signals.columns["force"]
    assert force[:50].max() == 0.0
    assert force[-1] > 10.0


def test_a_trajectory_with_nan_is_refused_before_execution(reference):
    positions = reference.positions.copy()
    positions[10, 1] = np.nan
    with pytest.raises(ExecutionError, match=r"not finite at sample 11"):
        Reference(reference.times, positions)


def test_rollout_model_defaults_to_the_expected_duration(learned_model):
    rollout = rollout_model(learned_model, SCENE, "kinematic", rate=10.0)
    assert rollout.signals.duration == pytest.approx(learned_model.expected_duration(), abs=0.1)


def test_one_skill_lasts_as_long_retrieved_and_executed(learned_model):
    from stl_lfd.hsmm import retrieve

    period = learned_model.sample_period_
    on_grid = period * round(learned_model.expected_duration() / period)
    retrieved = retrieve(learned_model).times[-1]
    executed = [rollout_model(learned_model, SCENE, "kinematic", rate=rate).signals.duration for rate in (100.0, 50.0)]
    assert retrieved == pytest.approx(on_grid) and executed == pytest.approx([on_grid, on_grid])


def test_a_rollout_after_one_that_pushed_into_the_floor_starts_without_force():
    times = np.linspace(0.0, 2.0, 481)
    hold = np.column_stack([np.full_like(times, 0.5), np.zeros_like(times), np.full_like(times, 0.4)])
    push = hold - np.column_stack([np.zeros_like(times), np.zeros_like(times), np.clip(times - 0.5, 0.0, 1.0) * 0.5 + 0.1])
    with new_backend("pybullet") as backend, warnings.catch_warnings():
        warnings.simplefilter("ignore", TrackingWarning)
        pushed = execute(Reference(times, push), SCENE, backend)
        after = execute(Reference(times, hold), SCENE, backend)
    assert pushed.signals.columns["force"].max() > 10.0
    assert np.all(after.signals.columns["force"] == 0.0)
