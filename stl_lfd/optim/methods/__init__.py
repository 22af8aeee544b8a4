"""Search methods: one class per method behind one protocol (`base.SearchMethod`), found by name.

    method = method_class("plan")(problem, optimizer)    # once per run
    method.propose(request)                               # -> [(x, phase), ...] for a batch

| name     | class                                    | what it does                                   |
|----------|------------------------------------------|------------------------------------------------|
| `stl`    | `stl.CompositeSearch`                    | composite BO on the spec's parts               |
| `plan`   | `plan.PlanSearch`                        | the same with each part's plan as prior        |
| `pi`     | `analytic.ProbabilityOfImprovement`      | the paper's probability of improvement         |
| `logei`  | `analytic.LogExpectedImprovementSearch`  | log expected improvement                       |
| `random` | `random.RandomSearch`                    | uniform random points (the baseline)           |

A new method is a `SearchMethod` subclass and one line in `REGISTRY` (or `register(name, cls)`
from outside the package). Classes are imported on first use: naming the methods, as the
command line does for its choices, loads no torch.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from stl_lfd.optim.methods.base import SearchMethod

REGISTRY: dict[str, "str | type[SearchMethod]"] = {
    "stl": "stl_lfd.optim.methods.stl:CompositeSearch",
    "plan": "stl_lfd.optim.methods.plan:PlanSearch",
    "pi": "stl_lfd.optim.methods.analytic:ProbabilityOfImprovement",
    "logei": "stl_lfd.optim.methods.analytic:LogExpectedImprovementSearch",
    "random": "stl_lfd.optim.methods.random:RandomSearch",
}


def method_names() -> tuple[str, ...]:
    """The registered methods' names, in the registry's order."""
    return tuple(REGISTRY)


def register(name: str, method: "type[SearchMethod]") -> None:
    """Make `method` available by `name` (task files, `--method`, `Optimizer(method=...)`)."""
    REGISTRY[name] = method


def method_class(name: str) -> "type[SearchMethod]":
    """The class registered as `name`."""
    entry = REGISTRY[name]
    if isinstance(entry, str):
        module, _, attribute = entry.partition(":")
        entry = REGISTRY[name] = getattr(import_module(module), attribute)
    return entry
