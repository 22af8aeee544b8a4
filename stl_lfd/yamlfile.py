"""Reading YAML files (scenes, task files) with errors that name the file, the key and the line.

Every reader checks its keys against what it knows, so that a typo is an error rather than a
silently ignored setting. `read_yaml` remembers where each key of the file is, so that a
`ConfigError` about `FILE: 'a.b[2].c' ...` is shown as `FILE:LINE:COLUMN: 'a.b[2].c' ...`
(see `stl_lfd.key_positions`).
"""

from __future__ import annotations

import re
from dataclasses import fields, is_dataclass, replace
from pathlib import Path
from typing import Any, Iterable

import yaml

from stl_lfd.dag import fold
from stl_lfd.errors import ConfigError
from stl_lfd.files import UnreadableFile, read_text
from stl_lfd.key_positions import remember

MAX_BYTES = 1_000_000  # task, scene and behaviour files are a few hundred bytes
MAX_NODES = 100_000  # values after expanding aliases (`*name`), against alias bombs


class _Loader(yaml.SafeLoader):
    """The safe loader, with duplicate keys refused and `1e9` read as a number (YAML 1.1 needs
    a dot, `1.0e9`, and would give the string '1e9')."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        seen: dict[Any, int] = {}
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            if isinstance(key, (str, int, float, bool)) and key in seen:
                raise yaml.constructor.ConstructorError(None, None, f"duplicate key '{key}' (first on line {seen[key]})", key_node.start_mark)
            if isinstance(key, (str, int, float, bool)):
                seen[key] = key_node.start_mark.line + 1
        return super().construct_mapping(node, deep)


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*)(?:\.[0-9_]*)?[eE][-+]?[0-9]+$"),
    list("-+0123456789"),
)


def read_yaml(path: Path | str) -> dict[str, Any]:
    """The top-level mapping of a YAML file; ConfigError for a missing, huge or bad file."""
    path = Path(path)
    try:
        text = read_text(path, "YAML file", MAX_BYTES)
    except UnreadableFile as error:
        raise ConfigError(f"{path}: {error}") from None
    try:
        loader = _Loader(text)
        try:
            root = loader.get_single_node()
            if root is not None and _expanded_size(root) > MAX_NODES:
                raise ConfigError(f"{path}: its aliases expand to more than {MAX_NODES} values; write the settings out")
            data = loader.construct_document(root) if root is not None else None
            _remember_positions(str(path), root)
        finally:
            loader.dispose()
    except RecursionError:
        raise ConfigError(f"{path}: the YAML nests too deeply to read; is it the right file?") from None
    except yaml.YAMLError as error:
        mark = getattr(error, "problem_mark", None) or getattr(error, "context_mark", None)
        where = f":{mark.line + 1}:{mark.column + 1}" if mark is not None else ""
        problem = getattr(error, "problem", None) or str(error)
        raise ConfigError(f"{path}{where}: invalid YAML ({problem})") from None
    if data is None:
        return {}
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping of keys at the top level")
    return data


def _remember_positions(name: str, root: yaml.Node | None) -> None:
    """Record where each key (and each list item) of the document starts."""
    positions: dict[str, tuple[int, int]] = {}
    stack: list[tuple[str, yaml.Node]] = [("", root)] if root is not None else []
    while stack and len(positions) <= MAX_NODES:
        prefix, node = stack.pop()
        if isinstance(node, yaml.MappingNode):
            for key_node, value_node in node.value:
                if isinstance(key_node, yaml.ScalarNode):
                    key = f"{prefix}.{key_node.value}" if prefix else str(key_node.value)
                    positions.setdefault(key, (key_node.start_mark.line + 1, key_node.start_mark.column + 1))
                    stack.append((key, value_node))
        elif isinstance(node, yaml.SequenceNode):
            for index, item in enumerate(node.value):
                key = f"{prefix}[{index}]"
                positions.setdefault(key, (item.start_mark.line + 1, item.start_mark.column + 1))
                stack.append((key, item))
    remember(name, positions)


def _expanded_size(root: yaml.Node) -> int:
    """The number of values the document has once every alias is expanded (shared nodes
    counted once per use), computed without expanding anything."""
    return fold(root, _children, lambda node, sizes: min(1 + sum(sizes), MAX_NODES + 1))


def _children(node: yaml.Node) -> list[yaml.Node]:
    if isinstance(node, yaml.MappingNode):
        return [item for pair in node.value for item in pair]
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    return []


def shown(value: Any, limit: int = 60) -> str:
    """`repr(value)` for a message, cut to `limit` characters."""
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def check_keys(mapping: Any, allowed: Iterable[str], path: Path | str, where: str = "", required: Iterable[str] = ()) -> dict[str, Any]:
    """`mapping` itself, after checking that it is a mapping with known keys and the required ones."""
    label = f"{path}: {where}" if where else f"{path}:"
    if not isinstance(mapping, dict):
        raise ConfigError(f"{label.rstrip(':')} must be a mapping of keys")
    allowed = list(allowed)
    for key in mapping:
        if key not in allowed:
            raise ConfigError(f"{path}: unknown key '{_join(where, shown(key)[1:-1] if isinstance(key, str) else shown(key))}' (known: {', '.join(allowed)})")
    for key in required:
        if key not in mapping:
            raise ConfigError(f"{path}: missing key '{_join(where, key)}'")
    return mapping


def number(value: Any, path: Path | str, key: str, positive: bool = False, minimum: float | None = None) -> float:
    """`value` as a float, with a ConfigError naming `key` when it is not a (positive) number."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ConfigError(f"{path}: '{key}' must be a number (got {shown(value)})")
    value = float(value)
    if value != value or value in (float("inf"), float("-inf")):
        raise ConfigError(f"{path}: '{key}' must be finite (got {value})")
    if positive and value <= 0:
        raise ConfigError(f"{path}: '{key}' must be positive (got {value:g})")
    if minimum is not None and value < minimum:
        raise ConfigError(f"{path}: '{key}' must be at least {minimum:g} (got {value:g})")
    return value


def integer(value: Any, path: Path | str, key: str, minimum: int | None = None, maximum: int | None = None) -> int:
    """`value` as an int (a whole float such as `1e3` counts), with a ConfigError naming `key`
    otherwise."""
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int):
        raise ConfigError(f"{path}: '{key}' must be an integer (got {shown(value)})")
    if minimum is not None and value < minimum:
        raise ConfigError(f"{path}: '{key}' must be at least {minimum} (got {value})")
    if maximum is not None and value > maximum:
        raise ConfigError(f"{path}: '{key}' must be at most {maximum} (got {shown(value)})")
    return value


def truth(value: Any, path: Path | str, key: str) -> bool:
    """`value` when it is true or false, with a ConfigError naming `key` otherwise."""
    if not isinstance(value, bool):
        raise ConfigError(f"{path}: '{key}' must be true or false (got {shown(value)})")
    return value


def vector(value: Any, length: int, path: Path | str, key: str) -> tuple[float, ...]:
    """`value` as a tuple of `length` finite floats."""
    if not isinstance(value, (list, tuple)) or len(value) != length:
        raise ConfigError(f"{path}: '{key}' must be a list of {length} numbers (got {shown(value)})")
    return tuple(number(item, path, f"{key}[{index}]") for index, item in enumerate(value))


def settings_from_yaml(defaults: Any, data: Any, path: Path | str, where: str) -> Any:
    """A copy of the frozen dataclass `defaults` with the fields `data` sets: whole numbers of at
    least 1 where the default is an int, true or false where it is a bool, numbers of at least 0
    where it is a float, lists of such numbers for tuples, and nested dataclasses the same way."""
    item = check_keys(data, [entry.name for entry in fields(defaults)], path, where)
    values = {}
    for name, value in item.items():
        default, key = getattr(defaults, name), _join(where, name)
        if is_dataclass(default):
            values[name] = settings_from_yaml(default, value, path, key)
        elif isinstance(default, tuple):
            if not isinstance(value, list) or not value:
                raise ConfigError(f"{path}: '{key}' must be a non-empty list of numbers (got {shown(value)})")
            values[name] = tuple(number(entry, path, f"{key}[{index}]", minimum=0.0) for index, entry in enumerate(value))
        elif isinstance(default, bool):
            values[name] = truth(value, path, key)
        elif isinstance(default, int):
            values[name] = integer(value, path, key, minimum=1)
        else:
            values[name] = number(value, path, key, minimum=0.0)
    return replace(defaults, **values)


def settings_to_yaml(settings: Any, defaults: Any) -> dict[str, Any]:
    """The fields of the frozen dataclass `settings` that differ from `defaults`, as YAML data
    (`settings_from_yaml` reads them back)."""
    data = {}
    for entry in fields(settings):
        value, default = getattr(settings, entry.name), getattr(defaults, entry.name)
        if value != default:
            data[entry.name] = settings_to_yaml(value, default) if is_dataclass(value) else list(value) if isinstance(value, tuple) else value
    return data


def _join(where: str, key: str) -> str:
    return f"{where}.{key}" if where else str(key)
