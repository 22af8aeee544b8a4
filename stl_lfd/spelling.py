"""How a message names a setting the user gave: as the command line spells it while `stlopt`
runs a command (the CLI sets its spellings for the command's duration, `spelled_as`), and by
the setting's own name, as task files and the Python API call it, otherwise. Lower modules
write `spelled("trials")`, never `--iterations`: the options' spellings are the CLI's alone."""

from __future__ import annotations

from contextvars import ContextVar
from types import MappingProxyType
from typing import Callable, Mapping

_SPELLINGS: ContextVar[Mapping[str, str]] = ContextVar("spellings", default=MappingProxyType({}))


def spelled(setting: str) -> str:
    """`setting` as the user gave it: `--iterations` for `trials` on the command line, `'trials'`
    from Python."""
    return _SPELLINGS.get().get(setting, f"'{setting}'")


def spelled_as(spellings: Mapping[str, str]) -> Callable[[], None]:
    """Name settings by `spellings` (setting -> how the user writes it) from now on; returns
    the function that restores the names used before."""
    token = _SPELLINGS.set(MappingProxyType(dict(spellings)))
    return lambda: _SPELLINGS.reset(token)
