"""The search methods by name: `REGISTRY` maps each name to its class, given as
`module:Class` text until first use (see `stl_lfd.optim.methods`). It imports nothing of the
optimiser, so that the settings can check a method's name without importing the methods."""

from __future__ import annotations

from importlib import import_module

REGISTRY: dict[str, str | type] = {
    "stl": "stl_lfd.optim.methods.stl:CompositeSearch",
    "plan": "stl_lfd.optim.methods.plan:PlanSearch",
    "pi": "stl_lfd.optim.methods.analytic:ProbabilityOfImprovement",
    "logei": "stl_lfd.optim.methods.analytic:LogExpectedImprovementSearch",
    "random": "stl_lfd.optim.methods.random:RandomSearch",
}


def method_names() -> tuple[str, ...]:
    """The registered methods' names, in the registry's order."""
    return tuple(REGISTRY)


def register(name: str, method: type) -> None:
    """Make `method` (a `SearchMethod` subclass) available by `name` (task files, `--method`, `Optimizer(method=...)`)."""
    REGISTRY[name] = method


def method_class(name: str) -> type:
    """The class registered as `name` (a `SearchMethod` subclass)."""
    entry = REGISTRY[name]
    if isinstance(entry, str):
        module, _, attribute = entry.partition(":")
        entry = REGISTRY[name] = getattr(import_module(module), attribute)
    return entry
