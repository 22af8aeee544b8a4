"""HSMM: recovery from sampled data, state sequences, LQT against the batch solution, files."""

from pathlib import Path

import numpy as np
import pytest

from stl_lfd.errors import ModelError
from stl_lfd.hsmm import HSMM, load_model, lqt, retrieve, save_model
from stl_lfd.hsmm._forward import duration_pmf, state_occupancy
from stl_lfd.hsmm.em import gaussian_log_density
from stl_lfd.hsmm.retrieval import hermite_interpolation

PERIOD = 0.01


def known_model(duration_std: float = 0.08) -> HSMM:
    model = HSMM(n_states=4)
    model.means_ = np.array([[0.0, 0.0], [0.3, 0.0], [0.3, 0.3], [0.0, 0.3]])
    model.covars_ = np.array([np.eye(2) * 1e-4] * 4)
    model.duration_means_ = np.array([0.6, 1.0, 0.8, 0.7])
    model.duration_stds_ = np.full(4, duration_std)
    model.transmat_ = np.eye(4, k=1)
    model.startprob_ = np.eye(4)[0]
    model.sample_period_ = PERIOD
    model.signal_names_ = ["x", "y"]
    return model


def test_learning_recovers_a_known_model():
    truth = known_model()
    samples = [truth.sample(3.4, seed) for seed in range(6)]
    X = np.concatenate([x for x, _ in samples])
    lengths = np.array([len(x) for x, _ in samples])
    model = HSMM(n_states=4).fit(X, lengths, PERIOD, ["x", "y"])
    np.testing.assert_allclose(model.means_, truth.means_, atol=0.005)  # 5 mm
    # Durations: the last state is cut by the end of each sample, so compare the first three.
    np.testing.assert_allclose(model.duration_means_[:3], truth.duration_means_[:3], atol=0.06)
    np.testing.assert_allclose(model.transmat_, truth.transmat_, atol=1e-6)
    # Segmentation: the most likely states match the generating ones almost everywhere.
    predicted = model.predict(X, lengths)
    true_states = np.concatenate([states for _, states in samples])
    assert np.mean(predicted == true_states) > 0.99


def test_state_sequence_switches_at_cumulative_duration_means():
    model = known_model(duration_std=0.004)  # well under one step
    states = model.state_sequence(400)
    switches = np.flatnonzero(np.diff(states)) + 1
    expected = np.round(np.cumsum(model.duration_means_[:3]) / PERIOD).astype(int)
    assert list(switches) == list(expected)


def six_state_band_model() -> HSMM:
    model = HSMM(n_states=6)
    model.means_ = np.arange(12, dtype=float).reshape(6, 2) * 0.05
    model.covars_ = np.array([np.eye(2) * 1e-4] * 6)
    model.duration_means_ = np.array([2.0, 4.7, 3.0, 1.5, 7.0, 4.0])
    model.duration_stds_ = np.array([0.35, 0.7, 0.3, 0.5, 0.7, 0.4])
    model.transmat_ = np.eye(6, k=1)
    model.startprob_ = np.eye(6)[0]
    model.sample_period_ = PERIOD
    model.signal_names_ = ["x", "y"]
    return model


def assert_is_a_path(model: HSMM, states: np.ndarray) -> None:
    transmat = model.normalized_transmat()
    assert model.startprob_[states[0]] > 0
    switches = np.flatnonzero(np.diff(states)) + 1
    for step in switches:
        assert transmat[states[step - 1], states[step]] > 0, (states[step - 1], states[step])
    visited = [states[0]] + [states[step] for step in switches]
    assert visited == model.nominal_path()


def test_state_sequence_is_a_path_when_a_state_branches():
    # Row 3 splits 0.45 / 0.55 between states 4 and 5: the occupancy's argmax went
    # 1 -> 2 -> 3 -> 4 -> 6 (4 -> 6 has probability 0); the sequence follows 3 -> 5 -> 6.
    model = six_state_band_model()
    model.transmat_[2] = [0, 0, 0, 0.45, 0.55, 0]
    steps = int(25 / PERIOD)
    states = model.state_sequence(steps)
    assert_is_a_path(model, states)
    assert model.nominal_path() == [0, 1, 2, 4, 5]
    # The last state starts after the duration means of the states before it.
    start_of_last = np.flatnonzero(states == 5)[0] * PERIOD
    assert start_of_last == pytest.approx(model.expected_duration() - model.duration_means_[5], abs=PERIOD)


@pytest.mark.parametrize("tilt", [0.0, 1e-12, -1e-12, 1e-6, -1e-6])
def test_near_ties_give_a_path_consistent_with_the_expected_duration(tilt):
    model = six_state_band_model()
    model.transmat_[1] = [0, 0, 0.5 + tilt, 0.5 - tilt, 0, 0]
    states = model.state_sequence(int(25 / PERIOD))
    assert_is_a_path(model, states)
    expected_successor = 3 if tilt < 0 else 2  # an exact tie goes to the lower state number
    assert model.nominal_path()[2] == expected_successor
    last = model.nominal_path()[-1]
    start_of_last = np.flatnonzero(states == last)[0] * PERIOD
    assert start_of_last == pytest.approx(model.expected_duration() - model.duration_means_[last], abs=PERIOD)


def test_random_transition_matrices_always_give_paths():
    rng = np.random.default_rng(0)
    for _ in range(50):
        model = six_state_band_model()
        model.transmat_ = rng.random((6, 6)) * (rng.random((6, 6)) < 0.5)
        np.fill_diagonal(model.transmat_, 0.0)
        model.duration_means_ = rng.uniform(0.001, 3.0, 6)  # some shorter than a step
        assert_is_a_path(model, model.state_sequence(int(12 / PERIOD)))


def test_no_probability_mass_leaks():
    model = known_model(duration_std=0.2)
    pmf = duration_pmf(model.duration_means_ / PERIOD, model.duration_stds_ / PERIOD, 200)
    occupancy = state_occupancy(model.startprob_, model.normalized_transmat(), pmf, 600)
    np.testing.assert_allclose(occupancy.sum(axis=1), 1.0, atol=1e-9)
    assert occupancy[-1, 3] > 0.999  # the final state absorbs long after the nominal end


def test_occupancy_matches_a_step_by_step_recursion():
    rng = np.random.default_rng(3)
    transmat = np.array([[0, 0.7, 0.3], [0, 0, 1.0], [0, 0, 0]])
    pmf = rng.uniform(size=(3, 12))
    pmf /= pmf.sum(axis=1, keepdims=True)
    start = np.array([1.0, 0, 0])
    fast = state_occupancy(start, transmat, pmf, 40)
    renewal = transmat.copy()
    renewal[2, 2] = 1.0
    a = start[:, None] * pmf  # a(i, d), d = 1..12
    slow = []
    for _ in range(40):
        slow.append(a.sum(axis=1) / a.sum())
        entering = a[:, 0] @ renewal
        a = np.concatenate([a[:, 1:], np.zeros((3, 1))], axis=1) + entering[:, None] * pmf
    np.testing.assert_allclose(fast, np.array(slow), atol=1e-10)


def batch_lqt(A, B, Q, R, targets, x0):
    """The lifted least-squares solution: cubic, obviously right, for small problems."""
    steps, n = targets.shape
    m = B.shape[1]
    Sx = np.vstack([np.linalg.matrix_power(A, t) for t in range(steps)])
    Su = np.zeros((steps * n, (steps - 1) * m))
    for t in range(1, steps):
        for s in range(t):
            Su[t * n : (t + 1) * n, s * m : (s + 1) * m] = np.linalg.matrix_power(A, t - 1 - s) @ B
    Qb = np.zeros((steps * n, steps * n))
    for t in range(steps):
        Qb[t * n : (t + 1) * n, t * n : (t + 1) * n] = Q[t]
    Rb = np.kron(np.eye(steps - 1), R)
    u = np.linalg.solve(Su.T @ Qb @ Su + Rb, Su.T @ Qb @ (targets.ravel() - Sx @ x0))
    return (Sx @ x0 + Su @ u).reshape(steps, n)


@pytest.mark.parametrize("segmented", [False, True])
def test_riccati_equals_batch_lqt(segmented):
    rng = np.random.default_rng(0)
    A, B = lqt.double_integrator(2, 0.1)
    steps = 36
    ids = np.repeat(np.arange(4), 9) if segmented else np.arange(steps)
    count = ids.max() + 1
    Q = np.zeros((count, 4, 4))
    for k in range(count):
        L = rng.normal(size=(2, 2))
        Q[k, :2, :2] = L @ L.T + np.eye(2)
    targets = np.zeros((count, 4))
    targets[:, :2] = rng.normal(size=(count, 2))
    x0, R = rng.normal(size=4), 0.01 * np.eye(2)
    states, _ = lqt.solve(A, B, Q, R, targets, x0, segment_ids=ids if segmented else None)
    np.testing.assert_allclose(states, batch_lqt(A, B, Q[ids], R, targets[ids], x0), atol=1e-8)


def test_retrieval_follows_modified_parameters():
    model = known_model()
    model.means_[1] += [0.0, 0.1]
    model.duration_means_[0] *= 2
    model.transmat_ = np.array([[0, 3.0, 1.0, 0], [0, 0, 1, 0], [0, 0, 0, 1], [0, 0, 0, 0]])  # unnormalised row
    np.testing.assert_allclose(model.normalized_transmat()[0], [0, 0.75, 0.25, 0])
    moved = retrieve(model)
    first_switch = np.flatnonzero(np.diff(moved.states))[0] + 1
    assert abs(first_switch - round(1.2 / PERIOD)) <= 1  # argmax of a spread-out duration
    in_second_state = moved.positions[moved.states == 1]
    assert np.min(np.linalg.norm(in_second_state - model.means_[1], axis=1)) < 0.01


@pytest.mark.parametrize("spacing", ["even", "uneven"])
def test_hermite_interpolation_is_scipys_cubic_hermite_spline_bit_for_bit(spacing):
    from scipy.interpolate import CubicHermiteSpline

    rng = np.random.default_rng(3)
    times = np.arange(200) * 0.04 if spacing == "even" else np.cumsum(rng.random(200) + 0.01)
    positions, velocities = rng.normal(size=(200, 3)), rng.normal(size=(200, 3))
    new_times = np.concatenate([[times[0] - 0.5], np.arange(int(times[-1] * 240) + 1) / 240, [times[-1], times[-1] + 0.3]])
    spline = CubicHermiteSpline(times, positions, velocities, axis=0)
    new_positions, new_velocities = hermite_interpolation(times, positions, velocities, new_times)
    np.testing.assert_array_equal(new_positions, spline(new_times))
    np.testing.assert_array_equal(new_velocities, spline(new_times, 1))


def test_gaussian_log_density_is_scipys_multivariate_normal_bit_for_bit():
    from scipy.stats import multivariate_normal

    rng = np.random.default_rng(4)
    points = rng.normal(size=(3, 50, 3))
    factor = rng.normal(size=(3, 3))
    singular = np.outer(factor[0], factor[0]) + np.outer(factor[1], factor[1])  # rank 2
    on_plane = points @ np.linalg.svd(singular)[0][:, :2] @ np.linalg.svd(singular)[0][:, :2].T
    for covariance, where in [(factor @ factor.T + 0.1 * np.eye(3), points), (singular, points), (singular, on_plane)]:
        mean = rng.normal(size=3)
        expected = multivariate_normal(mean, covariance, allow_singular=True).logpdf(where + mean * (where is on_plane))
        np.testing.assert_array_equal(gaussian_log_density(where + mean * (where is on_plane), mean, covariance), expected)
    assert np.isinf(gaussian_log_density(points, mean, singular)).any() and np.isfinite(gaussian_log_density(on_plane + mean, mean, singular)).all()


def test_save_load_round_trip(tmp_path: Path):
    model = known_model()
    save_model(model, tmp_path / "m.npz")
    loaded = load_model(tmp_path / "m.npz")
    for name in ("means_", "covars_", "duration_means_", "duration_stds_", "transmat_", "startprob_"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(model, name))
    assert loaded.signal_names_ == ["x", "y"] and loaded.sample_period_ == PERIOD
    np.testing.assert_array_equal(retrieve(loaded).positions, retrieve(model).positions)


def test_model_file_errors(tmp_path: Path):
    with pytest.raises(ModelError, match="no such model file"):
        load_model(tmp_path / "none.npz")
    (tmp_path / "junk.npz").write_text("not a zip")
    with pytest.raises(ModelError, match="not a model file"):
        load_model(tmp_path / "junk.npz")
    np.savez(tmp_path / "other.npz", a=np.zeros(2))
    with pytest.raises(ModelError, match="not an stlopt model file"):
        load_model(tmp_path / "other.npz")
    model = known_model()
    save_model(model, tmp_path / "future.npz")
    data = dict(np.load(tmp_path / "future.npz"))
    data["format_version"] = np.array(99)
    np.savez(tmp_path / "future.npz", **data)
    with pytest.raises(ModelError, match="newer than this stlopt"):
        load_model(tmp_path / "future.npz")


def test_check_rejects_bad_parameters():
    model = known_model()
    model.duration_means_ = np.array([0.6, -1.0, 0.8, 0.7])
    with pytest.raises(ModelError, match="duration means and stds must be positive"):
        retrieve(model)
    model = known_model()
    model.covars_ = np.zeros((3, 2, 2))
    with pytest.raises(ModelError, match=r"covars_ must have shape \(4, 2, 2\)"):
        model.state_sequence(10)
