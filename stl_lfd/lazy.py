"""Package attributes and registered classes loaded on first use, so that importing a package
(or naming what a registry holds) stays cheap."""

from __future__ import annotations

from importlib import import_module
from typing import Any, Callable


def lazy_exports(package: str, homes: dict[str, str], namespace: dict[str, Any]) -> tuple[list[str], Callable[[str], Any], Callable[[], list[str]]]:
    """`__all__`, `__getattr__` and `__dir__` for a package whose names live in other modules.

    Args:
        package: the package's name, for error messages.
        homes: exported name -> module that defines it.
        namespace: the package's `globals()`; a name is stored there once loaded.
    """

    def __getattr__(name: str) -> Any:
        if name not in homes:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(import_module(homes[name]), name)
        namespace[name] = value
        return value

    def __dir__() -> list[str]:
        return sorted(set(namespace) | set(homes))

    return sorted(homes), __getattr__, __dir__


def loaded(target: str | Any) -> Any:
    """The attribute a `module:Name` string names, imported now; anything else as it is."""
    if not isinstance(target, str):
        return target
    module, _, attribute = target.partition(":")
    return getattr(import_module(module), attribute)
