"""Reading YAML files (scenes, task files) with errors that name the file, the key and the line.

Every reader checks its keys against what it knows, so that a typo is an error rather than a
silently ignored setting.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Iterable

import yaml

from stl_lfd.errors import ConfigError


def read_yaml(path: Path | str) -> dict[str, Any]:
    """The top-level mapping of a YAML file; ConfigError for a missing file or bad YAML."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as error:
        raise ConfigError(f"{path}: cannot read ({error.strerror or error})") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None)
        where = f":{mark.line + 1}:{mark.column + 1}" if mark is not None else ""
        problem = getattr(error, "problem", None) or str(error)
        raise ConfigError(f"{path}{where}: invalid YAML ({problem})") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping of keys at the top level")
    return data


def check_keys(mapping: Any, allowed: Iterable[str], path: Path | str, where: str = "", required: Iterable[str] = ()) -> dict[str, Any]:
    """`mapping` itself, after checking that it is a mapping with known keys and the required ones."""
    label = f"{path}: {where}" if where else f"{path}:"
    if not isinstance(mapping, dict):
        raise ConfigError(f"{label.rstrip(':')} must be a mapping of keys")
    allowed = list(allowed)
    for key in mapping:
        if key not in allowed:
            raise ConfigError(f"{path}: unknown key '{_join(where, key)}' (known: {', '.join(allowed)})")
    for key in required:
        if key not in mapping:
            raise ConfigError(f"{path}: missing key '{_join(where, key)}'")
    return mapping


def number(value: Any, path: Path | str, key: str, positive: bool = False, minimum: float | None = None) -> float:
    """`value` as a float, with a ConfigError naming `key` when it is not a (positive) number."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"{path}: '{key}' must be a number (got {value!r})")
    value = float(value)
    if value != value or value in (float("inf"), float("-inf")):
        raise ConfigError(f"{path}: '{key}' must be finite (got {value})")
    if positive and value <= 0:
        raise ConfigError(f"{path}: '{key}' must be positive (got {value:g})")
    if minimum is not None and value < minimum:
        raise ConfigError(f"{path}: '{key}' must be at least {minimum:g} (got {value:g})")
    return value


def integer(value: Any, path: Path | str, key: str, minimum: int | None = None) -> int:
    """`value` as an int, with a ConfigError naming `key` otherwise."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise ConfigError(f"{path}: '{key}' must be an integer (got {value!r})")
    if minimum is not None and value < minimum:
        raise ConfigError(f"{path}: '{key}' must be at least {minimum} (got {value})")
    return value


def vector(value: Any, length: int, path: Path | str, key: str) -> tuple[float, ...]:
    """`value` as a tuple of `length` finite floats."""
    if not isinstance(value, (list, tuple)) or len(value) != length:
        raise ConfigError(f"{path}: '{key}' must be a list of {length} numbers (got {value!r})")
    return tuple(number(item, path, f"{key}[{index}]") for index, item in enumerate(value))


def _join(where: str, key: str) -> str:
    return f"{where}.{key}" if where else str(key)
