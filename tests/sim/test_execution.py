"""The backends on the learned skill: tracking, determinism, recorded signals, bad input; the
compliant arm's wrist sensor."""

import warnings

import numpy as np
import pytest

from stl_lfd.errors import ExecutionError
from stl_lfd.sim import Reference, TrackingWarning, execute, load_scene, new_backend
from stl_lfd.skill.execution import rollout_model
from stl_lfd.skill.reference import build_reference

SCENE = load_scene("free_space")


@pytest.fixture(scope="module")
def reference(learned_model):
    return build_reference({"skill": learned_model}, duration=20.0)


ENGINES = ["pybullet", "mujoco"]


@pytest.fixture(scope="module", params=ENGINES)
def simulated(request, reference):
    return request.param, execute(reference, SCENE, request.param, rate=100.0)


@pytest.mark.slow
def test_the_compliant_arm_tracks_the_retrieved_skill_within_1_mm(simulated):
    _, rollout = simulated
    assert rollout.tracking_rms < 0.001
    assert rollout.tracking_max < 0.002


@pytest.mark.slow
def test_recorded_signals_follow_the_signal_format(simulated):
    signals = simulated[1].signals
    assert list(signals.columns) == ["x", "y", "z", "gripper", "force", "qx", "qy", "qz", "qw", "tilt", "fx", "fy", "fz", "tx", "ty", "tz"]
    assert np.degrees(signals.columns["tilt"]).max() < 1.0  # the hand points down, as the reference asks
    assert signals.samples == 2001 and signals.times[-1] == pytest.approx(20.0)
    assert np.allclose(signals.columns["gripper"], SCENE.gripper_opening, atol=1e-3)
    assert signals.columns["force"].max() < 1.0  # nothing is touched in free space: the hand's own weight and motion are compensated
    assert np.allclose(signals.columns["force"], np.linalg.norm([signals.columns[name] for name in ("fx", "fy", "fz")], axis=0))


@pytest.mark.slow
def test_the_same_reference_gives_identical_signals(reference, simulated):
    engine, rollout = simulated
    again = execute(reference, SCENE, engine, rate=100.0)
    for name, values in rollout.signals.columns.items():
        assert np.array_equal(values, again.signals.columns[name]), name


def test_kinematic_backend_records_the_reference(reference):
    rollout = execute(reference, SCENE, "kinematic", rate=50.0)
    times = rollout.signals.times
    assert times.size == 1001
    assert np.allclose(rollout.signals.columns["x"], np.interp(times, reference.times, reference.positions[:, 0]))
    assert rollout.tracking_max == 0.0


@pytest.mark.slow
@pytest.mark.parametrize("engine", ENGINES)
def test_unreachable_targets_warn_with_the_worst_error(reference, engine):
    far = Reference(reference.times, reference.positions + np.array([0.6, 0.0, 0.0]))
    with pytest.warns(TrackingWarning, match=r"worst tracking error \d+\.\d mm at t = .* outside the workspace"):
        rollout = execute(far, SCENE, engine)
    assert rollout.tracking_max > 0.1


def press(depth: float, seconds: float = 3.0) -> Reference:
    """The hand, pointing down, sent from 0.3 m above the floor to `depth` m into it, then held."""
    times = np.arange(0.0, seconds, 1 / 240)
    lowered = np.clip((times - 0.5) / 1.0, 0.0, 1.0)
    heights = 0.3 - (0.3 + depth) * (10 * lowered**3 - 15 * lowered**4 + 6 * lowered**5)
    return Reference(times, np.column_stack([np.full_like(times, 0.5), np.zeros_like(times), heights]))


@pytest.mark.parametrize("engine", ENGINES)
def test_pressing_on_the_floor_reads_the_stiffness_times_the_depth(engine):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TrackingWarning)
        rollout = execute(press(0.02), SCENE, engine)
    columns, times = rollout.signals.columns, rollout.signals.times
    assert columns["force"][times < 0.4].max() < 0.5
    # the fingertips touch the floor while the grasp target is still about 8 mm above it
    held = columns["fz"][times > 2.5]
    stiffness = SCENE.control.translational_stiffness
    reached = 0.3 + 0.02 - (0.3 - columns["z"][times > 2.5])  # how far the equilibrium is below the hand
    assert held == pytest.approx(stiffness * reached, rel=0.05)
    assert np.abs(columns["fx"][times > 2.5]).max() < 0.5 and np.abs(columns["fy"][times > 2.5]).max() < 0.5


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


@pytest.mark.parametrize("engine", ENGINES)
def test_a_rollout_after_one_that_pushed_into_the_floor_starts_without_force(engine):
    times = np.linspace(0.0, 2.0, 481)
    hold = np.column_stack([np.full_like(times, 0.5), np.zeros_like(times), np.full_like(times, 0.4)])
    with new_backend(engine) as backend, warnings.catch_warnings():
        warnings.simplefilter("ignore", TrackingWarning)
        pushed = execute(press(0.05, 2.0), SCENE, backend)
        after = execute(Reference(times, hold), SCENE, backend)
    assert pushed.signals.columns["force"].max() > 10.0
    assert after.signals.columns["force"].max() < 0.1
