"""What every search method shares: the problem it searches, the request for a batch of points,
the protocol it implements, and the unit cube it works in.

A method is constructed once per run (`Problem`, the run's `Optimizer`) and asked for each
batch (`Request`); everything a proposal depends on is in the request (the history, the points
still executing, the trial numbers) and the run's seed, so a resumed run proposes exactly the
points an uninterrupted one did.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable, ClassVar, Hashable, Sequence

import numpy as np

from stl_lfd.optim.trials import Trial, observations

if TYPE_CHECKING:
    from stl_lfd.optim.settings import Optimizer
    from stl_lfd.stl import Semantics


@dataclass(frozen=True)
class Composition:
    """How the robustness is composed of the parts a trial records (`Trial.components`).

    Attributes:
        names: the parts' texts (at several placements: `placement i (...): PART`).
        semantics: how the parts of one group compose.
        groups: the parts are this many equal groups side by side (one per object placement),
            and the robustness is the minimum of the groups' compositions.
        routes: `(name, part)` of each formula that implies a part (`SpecParts.routes`).
    """

    names: tuple[str, ...]
    semantics: Semantics
    groups: int = 1
    routes: tuple[tuple[str, int], ...] = ()

    @property
    def route_names(self) -> tuple[str, ...]:
        return tuple(name for name, _ in self.routes)

    @property
    def route_parts(self) -> tuple[int, ...]:
        return tuple(part for _, part in self.routes)


@dataclass(frozen=True)
class Planner:
    """What the skill does at a point, known before executing it: its plan.

    Attributes:
        plan: the plan's robustness of each part, then route, at `b x d` points (parameter
            units) -> `b x o` values, planned together; raises when a point has no plan.
        tracked: history -> (key, plan): `plan` through the tracking model learned from the
            history's executions, for a robot that does not execute the plan (None: it does);
            the same key, the same model; `(None, None)` while the plan itself will do.
    """

    plan: Callable[[np.ndarray], np.ndarray]
    tracked: Callable[[Sequence[Trial]], tuple[Hashable | None, Callable[[np.ndarray], np.ndarray] | None]] | None = None

    def as_executed(self, history: Sequence[Trial]) -> tuple[Hashable | None, Callable[[np.ndarray], np.ndarray]]:
        """The plan as the robot will execute it, learned from `history`, and its key (None:
        the plan itself)."""
        key, tracked = self.tracked(history) if self.tracked is not None else (None, None)
        return (None, self.plan) if key is None else (key, tracked)


@dataclass(frozen=True)
class Problem:
    """What a run searches.

    Attributes:
        bounds: `2 x d` parameter bounds.
        composition: the spec's parts (None: the robustness alone).
        features: what a GP sees of `b x d` unit-cube points (`features.PathFeatures`, a
            torch tensor -> `b x f`); None: the points themselves.
        planner: the plan of a point (method `plan`'s prior); None: no plans.
        initial_design: the `M x d` Sobol points, when already computed (saves torch's import).
    """

    bounds: np.ndarray
    composition: Composition | None = None
    features: Callable | None = None
    planner: Planner | None = None
    initial_design: np.ndarray | None = None

    @property
    def dimension(self) -> int:
        return self.bounds.shape[1]


@dataclass(frozen=True)
class Request:
    """A batch to propose: trial indices `[first, first + count)` (0-based).

    Attributes:
        history: the finished trials the batch learns from (with parallel workers, those
            before the previous batch).
        pending: `p x d` points executing or already chosen, not observed yet.
        first, count: the batch's first trial index and size.
        seed: the run's seed.
    """

    history: Sequence[Trial]
    pending: np.ndarray
    first: int
    count: int
    seed: int

    def seed_for(self, index: int) -> int:
        """The seed of a proposal made for (or after) trial index `index`: every method's
        random draws and acquisition starts derive from the run's seed this way."""
        return self.seed + index

    @property
    def indices(self) -> range:
        return range(self.first, self.first + self.count)


Proposal = tuple[np.ndarray, str]  # a point and the phase that chose it


class SearchMethod(ABC):
    """A search method: `propose(request)` -> `request.count` points, each with its phase.

    Subclasses set `name` (as a task file names it), take their tuning in a frozen settings
    dataclass, and are registered by name in `stl_lfd.optim.methods`.
    """

    name: ClassVar[str]
    parallel: ClassVar[bool] = True  # whether it proposes batches (workers > 1)

    def __init__(self, problem: Problem, optimizer: Optimizer) -> None:
        self.problem, self.optimizer = problem, optimizer

    @abstractmethod
    def propose(self, request: Request) -> list[Proposal]:
        """`request.count` points (and phases) for the trials of `request.indices`."""


class SobolStart(SearchMethod):
    """A method whose M initial trials are the run's scrambled Sobol points, then `search`; while
    nothing can be modelled (every trial failed or gave the same value), uniform random points."""

    @abstractmethod
    def search(self, request: Request, X: np.ndarray, Y: np.ndarray) -> list[Proposal]:
        """The batch after the initial design, from `n x d` points `X` and `n` values `Y`."""

    def propose(self, request: Request) -> list[Proposal]:
        if request.first < self.optimizer.initial:
            return [(point, "sobol") for point in self.initial_design()[request.first : request.first + request.count]]
        X, Y = observations(request.history)
        if len(Y) == 0 or np.ptp(Y) == 0:
            return [(random_point(self.problem.bounds, request.seed, index), "random") for index in request.indices]
        return self.search(request, X, Y)

    def initial_design(self) -> np.ndarray:
        design = self.problem.initial_design
        return sobol_points(self.problem.bounds, self.optimizer.initial, self.optimizer.seed) if design is None else design


def sobol_points(bounds: np.ndarray, count: int, seed: int) -> np.ndarray:
    """`count x d` scrambled Sobol points inside `bounds` (`2 x d`), the same for the same seed."""
    import torch
    from torch.quasirandom import SobolEngine

    return from_unit(SobolEngine(bounds.shape[1], scramble=True, seed=seed).draw(count, dtype=torch.float64).numpy(), bounds)


def random_point(bounds: np.ndarray, seed: int, trial: int) -> np.ndarray:
    """A uniform point inside `bounds`, determined by the seed and the trial index alone."""
    return from_unit(np.random.default_rng([seed, trial]).random(bounds.shape[1]), bounds)


def to_unit(points: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    """`... x d` points in parameter units -> the unit cube of `bounds` (BoTorch's `normalize`)."""
    import torch
    from botorch.utils.transforms import normalize

    return normalize(torch.as_tensor(points, dtype=torch.float64), torch.as_tensor(bounds, dtype=torch.float64)).numpy()


def from_unit(unit: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    """`... x d` unit-cube points -> parameter units of `bounds` (BoTorch's `unnormalize`)."""
    import torch
    from botorch.utils.transforms import unnormalize

    return unnormalize(torch.as_tensor(unit, dtype=torch.float64), torch.as_tensor(bounds, dtype=torch.float64)).numpy()
