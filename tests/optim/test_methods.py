"""The search methods' registry: a new method is one class and one registry line, and the loop,
task files and `Optimizer` take it by name."""

import numpy as np
import pytest

from stl_lfd.errors import ConfigError
from stl_lfd.optim import methods
from stl_lfd.optim.loop import run_remaining_trials, search_method
from stl_lfd.optim.methods.base import Problem, Request, SearchMethod
from stl_lfd.optim.settings import Optimizer
from stl_lfd.optim.trials import Outcome

BOUNDS = np.array([[0.0, -1.0], [1.0, 1.0]])


class Corners(SearchMethod):
    """A toy method: the corners of the box in turn, whatever the history."""

    name = "corners"

    def propose(self, request: Request) -> list[tuple[np.ndarray, str]]:
        corners = [np.array([self.problem.bounds[i % 2, 0], self.problem.bounds[(i // 2) % 2, 1]]) for i in request.indices]
        return [(corner, "corners") for corner in corners]


@pytest.fixture
def registered(monkeypatch):
    monkeypatch.setitem(methods.REGISTRY, "corners", Corners)  # the one registry line


def test_a_new_method_is_one_class_and_one_registry_line(registered):
    optimizer = Optimizer("corners", initial=1, trials=5, workers=2)
    history = run_remaining_trials(lambda x: Outcome(float(x.sum())), search_method(optimizer, Problem(BOUNDS)), [], lambda trial, payload: None)
    assert [trial.phase for trial in history] == ["corners"] * 5
    assert [trial.x.tolist() for trial in history] == [[0.0, -1.0], [1.0, -1.0], [0.0, 1.0], [1.0, 1.0], [0.0, -1.0]]
    assert "corners" in methods.method_names()


def test_an_unknown_method_and_parallel_trials_of_a_sequential_one_are_refused():
    with pytest.raises(ConfigError, match="'optimizer.method' must be one of stl, plan, pi, logei, random"):
        Optimizer("corners")
    with pytest.raises(ConfigError, match="need method stl, plan or random"):
        Optimizer("logei", workers=2)


def test_every_registered_method_is_a_search_method_of_its_name():
    for name in methods.method_names():
        assert issubclass(methods.method_class(name), SearchMethod) and methods.method_class(name).name == name
