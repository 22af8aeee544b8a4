"""What the GP is given: failed trials and outliers made harmless (stl_lfd.optim.trials)."""

from __future__ import annotations

import numpy as np

from stl_lfd.optim.trials import Trial, observations, part_observations, without_outliers


def history(values, parts=None):
    rng = np.random.default_rng(0)
    return [
        Trial(number + 1, "sobol", rng.uniform(size=2), value, components=None if parts is None else dict(zip("ab", parts[number])))
        for number, value in enumerate(values)
    ]


def test_an_absurd_value_is_clipped_and_the_others_are_untouched():
    values = [-0.02, 0.01, 0.004, -0.013, 0.017, -1e300, 0.008]
    _, Y = observations(history(values))
    assert np.array_equal(np.delete(Y, 5), np.delete(values, 5))
    assert Y[5] == min(np.delete(values, 5))  # as a failed trial enters: the worst ordinary value
    _, high = observations(history([-0.02, 0.01, 1e308, -0.013, 0.017]))
    assert high[2] == -0.02  # an absurd "satisfied" is no better
    _, few = observations(history([0.1, -1e300]))
    assert few[1] == -1e300  # too few values to tell an outlier: left as they are


def test_a_saturating_part_is_not_mistaken_for_an_outlier():
    plateau = np.array([0.049, 0.0491, 0.0492, 0.0491, 0.0102, 0.049, 0.0491, 0.0493])
    assert np.array_equal(without_outliers(plateau), plateau)
    forces = np.array([1.9, 1.8, 1.95, -78.0, 1.7, -12.0, 1.99, 1.9])  # a collision is bad, not absurd
    assert np.array_equal(without_outliers(forces), forces)
    parts = part_observations(history([0.0] * 6, parts=[(0.1, 1.0), (0.2, 2.0), (0.15, 1.5), (1e305, 1.2), (0.12, 1.1), (0.18, 1.3)]), ("a", "b"))
    assert parts[3, 0] == 0.1 and np.array_equal(parts[:, 1], [1.0, 2.0, 1.5, 1.2, 1.1, 1.3])


def test_the_gp_stays_sane_after_an_absurd_trial():
    import warnings

    import torch

    from stl_lfd.optim.methods.gp import fit_gp

    X, Y = observations(history([-0.02, 0.01, 0.004, -0.013, 0.017, -1e300, 0.008, 0.011]))
    with warnings.catch_warnings():
        from botorch.exceptions.warnings import InputDataWarning

        warnings.simplefilter("error", InputDataWarning)  # no "not standardized"
        warnings.simplefilter("error", RuntimeWarning)  # no overflow
        model = fit_gp(X, Y, np.array([[0.0, 0.0], [1.0, 1.0]]))
        mean = model.posterior(torch.as_tensor(X)).mean.detach().numpy().ravel()
    assert np.all(np.isfinite(mean))
    assert np.corrcoef(mean[[0, 1, 2, 3, 4, 6, 7]], np.delete(Y, 5))[0, 1] > 0.5  # the ordinary trials still tell apart
