"""Each search method's tuning: a frozen dataclass per method, settable from a task file under
the method's name (`optimizer: {method: pi, pi: {xi: 0.2}}`) or from Python
(`Optimizer("pi", tuning={"pi": ProbabilityOfImprovementSettings(xi=0.2)})`).

They live apart from the methods so that reading a task file checks them without importing a
method (method `plan` imports torch). `method_registry.SETTINGS` names them by method."""

from __future__ import annotations

from dataclasses import dataclass, field

from stl_lfd.errors import ConfigError
from stl_lfd.optim.methods.trust_region import TrustRegion


@dataclass(frozen=True)
class AnalyticSettings:
    """Tuning of the acquisition's maximisation (methods `pi` and `logei`).

    Attributes:
        restarts, raw_samples: L-BFGS-B starts, chosen among raw random samples.
        iterations: L-BFGS-B iterations per restart (BoTorch's default is 200).
    """

    restarts: int = 8
    raw_samples: int = 256
    # BoTorch's 200 iterations spent 2-3 s per PI proposal on phi2-shaped problems (flat log-PI,
    # ~750 evaluations); with 60 the maximum found was within 3.5 % of its PI in half the time.
    iterations: int = 60


@dataclass(frozen=True)
class ProbabilityOfImprovementSettings(AnalyticSettings):
    """Tuning of method `pi`.

    Attributes:
        xi: the margin PI asks for, in standard deviations of the observed robustness
            (improvement means exceeding max(Y) + xi std(Y)); without it PI saturates and
            over-exploits.
    """

    xi: float = 0.1

    def __post_init__(self) -> None:
        if not self.xi >= 0:
            raise ConfigError(f"'pi.xi' must be at least 0 (got {self.xi})")


@dataclass(frozen=True)
class CompositeSettings:
    """Tuning of method `stl`.

    Attributes:
        restarts, raw_samples: the acquisition optimiser's starts, chosen among raw samples.
        around_anchor, anchor_spread: candidate starts drawn around each anchor trial, and
            their standard deviation in the unit cube (see `stl.anchored_starts`).
        stall_gain, stall_trials: an improvement below `stall_gain` of the distance to
            satisfaction is a stall; after `stall_trials` in a row, a space-filling trial.
        region: the trust region.
        balance: compose the parts and routes each on its own scale (`balance.py`), so that
            the units of the spec's predicates do not steer the search; false: as recorded.
    """

    restarts: int = 4
    raw_samples: int = 128
    around_anchor: int = 32
    anchor_spread: float = 0.1
    stall_gain: float = 0.1
    stall_trials: int = 2
    region: TrustRegion = field(default_factory=TrustRegion)
    balance: bool = True


@dataclass(frozen=True)
class Rounds:
    """Refinement rounds of method `plan`'s search: for each of `spreads` (unit cube), `draws`
    Gaussian draws around each of the `centres` best candidates so far."""

    spreads: tuple[float, ...]
    centres: int
    draws: int


@dataclass(frozen=True)
class PlanSettings:
    """Tuning of method `plan`.

    Attributes:
        pool: Sobol candidates whose plans are computed once per run.
        first_rounds: the first trial's search, chosen by the plan alone (once per run).
        rounds: later trials' search, kept cheap (40 plans): the trials' history carries it on.
        pending_spread: no point of a batch this close (unit cube, any coordinate) to another.
        balance: compose the parts and routes each on its own scale (`balance.py`): before a
            trial, their plans' spread over the pool; after, the spread of the trials' values.
    """

    pool: int = 128
    first_rounds: Rounds = field(default_factory=lambda: Rounds((0.1, 0.04, 0.015, 0.006), 4, 8))
    rounds: Rounds = field(default_factory=lambda: Rounds((0.08, 0.02), 3, 5))
    pending_spread: float = 0.05
    balance: bool = True
