"""The join measurement of `benchmarks/bench_joins.py`: where skills hand over, and the force
excess there above the reading just before."""

import numpy as np

from benchmarks.bench_joins import join_excesses, joins


def test_joins_are_where_the_skill_changes():
    skills = np.array(["pick"] * 3 + ["grasp"] * 2 + ["insert"] * 3)
    assert joins(skills, np.arange(8) * 0.5) == [(1.5, "pick -> grasp"), (2.5, "grasp -> insert")]


def test_the_excess_is_the_peak_after_a_join_above_the_median_before_it():
    times = np.arange(0, 4, 0.01)
    force = np.full_like(times, 1.0)
    force[(times > 2.0) & (times < 2.1)] = 13.0  # a spike just after the join at 2 s
    force[times > 3.0] = 50.0  # contact long after: not the join's
    assert join_excesses(times, force, [(2.0, "grasp -> insert")]) == [("grasp -> insert", 12.0)]
