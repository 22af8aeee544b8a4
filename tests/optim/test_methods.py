"""The search methods' registry: a new method is one class and one registry line, and the loop,
task files and `Optimizer` take it by name."""

from dataclasses import dataclass

import numpy as np
import pytest

from stl_lfd.errors import ConfigError
from stl_lfd.optim import methods
from stl_lfd.optim.loop import run_remaining_trials, search_method
from stl_lfd.optim.methods.base import Problem, Request, SearchMethod
from stl_lfd.optim.methods.tuning import PlanSettings, ProbabilityOfImprovementSettings
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


@dataclass(frozen=True)
class CornerSettings:
    start: int = 0  # which corner comes first


class TunedCorners(Corners):
    name = "tuned_corners"

    def __init__(self, problem, optimizer) -> None:
        super().__init__(problem, optimizer)
        self.settings = optimizer.tuning_for(self.name)

    def propose(self, request: Request) -> list[tuple[np.ndarray, str]]:
        shifted = Request(request.history, request.pending, request.first + self.settings.start, request.count, request.seed)
        return super().propose(shifted)


def test_a_method_takes_its_settings_from_the_optimizer(monkeypatch):
    monkeypatch.setitem(methods.REGISTRY, "tuned_corners", TunedCorners)
    monkeypatch.setitem(methods.SETTINGS, "tuned_corners", CornerSettings)
    first = [
        search_method(Optimizer("tuned_corners", initial=1, trials=5, tuning=tuning), Problem(BOUNDS)).propose(Request([], np.empty((0, 2)), 0, 1, 0))[0][0]
        for tuning in ({}, {"tuned_corners": CornerSettings(start=3)})
    ]
    assert first[0].tolist() == [0.0, -1.0] and first[1].tolist() == [1.0, 1.0]
    with pytest.raises(ConfigError, match="'optimizer.tuned_corners' must be a CornerSettings"):
        Optimizer("tuned_corners", tuning={"tuned_corners": PlanSettings()})
    with pytest.raises(ConfigError, match="settings are for the methods"):
        Optimizer("plan", tuning={"random": PlanSettings()})


def test_pi_reads_its_margin_from_its_settings():
    problem = Problem(BOUNDS)
    default = search_method(Optimizer("pi"), problem)
    tuned = search_method(Optimizer("pi", tuning={"pi": ProbabilityOfImprovementSettings(xi=0.5, restarts=2)}), problem)
    assert default.settings.xi == 0.1 and (tuned.settings.xi, tuned.settings.restarts) == (0.5, 2)
    with pytest.raises(ConfigError, match="'pi.xi' must be at least 0"):
        ProbabilityOfImprovementSettings(xi=-1.0)
