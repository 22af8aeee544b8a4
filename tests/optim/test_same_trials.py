"""The optimiser gives the trials it was recorded giving (`same_trials.py`): every method on three
kinematic suite problems, the lagging robot, two workers, and phi1/phi2 on PyBullet.

A change that means to change the trials records them anew (`python -m tests.optim.same_trials
--write`) and says so. On another kind of processor than the record's, only the trials that no
model decides are compared (see `same_trials.py`).
"""

from __future__ import annotations

import json

import pytest

from benchmarks.bench_suite import processor
from tests.optim.same_trials import CASES, RECORD, differences, run_case

RECORDED = json.loads(RECORD.read_text())


@pytest.mark.slow
@pytest.mark.parametrize("name, task_file, overrides", CASES, ids=[case[0] for case in CASES])
def test_the_optimiser_gives_the_recorded_trials(name, task_file, overrides):
    assert differences(RECORDED["cases"][name], run_case(task_file, overrides), model_free_only=processor() != RECORDED["processor"]) == []


def test_the_record_holds_model_free_trials_and_model_decided_ones_for_every_method():
    phases = {phase for trials in RECORDED["cases"].values() for phase in (trial["phase"] for trial in trials)}
    assert {"design", "sobol", "random"} <= phases and {"plan", "stl", "pi", "logei"} <= phases
