"""Quaternion paths made continuous: the vectorised sign choice against its definition."""

import numpy as np
import pytest

from stl_lfd import rotations


def _one_at_a_time(q: np.ndarray) -> np.ndarray:
    """The definition: each sample flipped when its product with the previous one, as left, is negative."""
    q = np.array(q, dtype=float)
    for index in range(1, len(q)):
        if q[index] @ q[index - 1] < 0:
            q[index] = -q[index]
    return q


@pytest.mark.parametrize("seed", range(5))
def test_continuous_flips_the_samples_the_definition_flips(seed):
    rng = np.random.default_rng(seed)
    for length in (0, 1, 2, 3, 17, 400):
        q = rng.normal(size=(length, 4))
        if length > 3:
            q[length // 2] = 0.0  # a zero product: the next sample starts over unflipped
            q[1], q[2] = [1.0, 0, 0, 0], [0, 1.0, 0, 0]  # orthogonal neighbours
        assert np.array_equal(rotations.continuous(q), _one_at_a_time(q))


def test_a_path_through_the_antipode_stays_on_one_side():
    angles = np.linspace(0, 4 * np.pi, 50)
    q = np.column_stack([np.cos(angles / 2), np.zeros(50), np.zeros(50), np.sin(angles / 2)])
    q[1::2] *= -1
    path = rotations.continuous(q)
    assert np.all(np.einsum("ij,ij->i", path[1:], path[:-1]) > 0)
