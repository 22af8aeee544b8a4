"""The search methods by name: `REGISTRY` maps each name to its class and `SETTINGS` to the
class of its tuning (`methods.tuning`; a method without one is absent), both given as
`module:Class` text until first use (see `stl_lfd.optim.methods`). It imports nothing of the
optimiser, so that the settings can check a method's name without importing the methods."""

from __future__ import annotations

from stl_lfd.lazy import loaded

REGISTRY: dict[str, str | type] = {
    "stl": "stl_lfd.optim.methods.stl:CompositeSearch",
    "plan": "stl_lfd.optim.methods.plan:PlanSearch",
    "pi": "stl_lfd.optim.methods.analytic:ProbabilityOfImprovement",
    "logei": "stl_lfd.optim.methods.analytic:LogExpectedImprovementSearch",
    "random": "stl_lfd.optim.methods.random:RandomSearch",
}
SETTINGS: dict[str, str | type] = {
    "stl": "stl_lfd.optim.methods.tuning:CompositeSettings",
    "plan": "stl_lfd.optim.methods.tuning:PlanSettings",
    "pi": "stl_lfd.optim.methods.tuning:ProbabilityOfImprovementSettings",
    "logei": "stl_lfd.optim.methods.tuning:AnalyticSettings",
}


def method_names() -> tuple[str, ...]:
    """The registered methods' names, in the registry's order."""
    return tuple(REGISTRY)


def tuned_method_names() -> tuple[str, ...]:
    """The names of the methods that take settings, in the registry's order."""
    return tuple(name for name in REGISTRY if name in SETTINGS)


def register(name: str, method: type, settings: type | None = None) -> None:
    """Make `method` (a `SearchMethod` subclass) available by `name` (task files, `--method`,
    `Optimizer(method=...)`), with its tuning's frozen dataclass `settings` (None: no tuning)."""
    REGISTRY[name] = method
    if settings is not None:
        SETTINGS[name] = settings


def method_class(name: str) -> type:
    """The class registered as `name` (a `SearchMethod` subclass)."""
    return _resolved(REGISTRY, name)


def settings_class(name: str) -> type | None:
    """The tuning dataclass of the method registered as `name` (None: it takes no settings)."""
    return _resolved(SETTINGS, name) if name in SETTINGS else None


def _resolved(registry: dict[str, str | type], name: str) -> type:
    registry[name] = loaded(registry[name])
    return registry[name]
