"""Constant thresholds on single signals that a spec compares against (`force < 2.0`,
`shaft_tilt < 0.05`, `shaft_depth > 0.01`), so that figures can draw them on the signals."""

from __future__ import annotations

from dataclasses import dataclass

from stl_lfd.stl import ast


@dataclass(frozen=True)
class Threshold:
    """`signal op value`, read with the signal on the left (`2 > force` is `force < 2`)."""

    signal: str
    op: str
    value: float

    def __str__(self) -> str:
        return f"{self.signal} {self.op} {self.value:g}"


FLIPPED = {"<": ">", "<=": ">=", ">": "<", ">=": "<="}


def signal_thresholds(spec: ast.Spec) -> dict[str, list[Threshold]]:
    """Signal name -> the distinct thresholds of the comparisons between that signal alone and a
    number in the spec's formula, through the definitions it uses; in the order first met."""
    definitions = {definition.name: definition.formula for definition in spec.definitions}
    found: dict[str, list[Threshold]] = {}
    visited: set[str] = set()
    pending: list[ast.Node] = [spec.formula]
    while pending:
        node = pending.pop()
        if isinstance(node, ast.Ref) and node.name in definitions and node.name not in visited:
            visited.add(node.name)
            pending.append(definitions[node.name])
        threshold = _threshold(node)
        if threshold is not None and threshold not in found.setdefault(threshold.signal, []):
            found[threshold.signal].append(threshold)
        pending.extend(reversed(node.children()))
    return {signal: thresholds for signal, thresholds in found.items() if thresholds}


def _threshold(node: ast.Node) -> Threshold | None:
    found = node.signal_versus_number() if isinstance(node, ast.Compare) else None
    if found is None:
        return None
    signal, value, on_the_left = found
    return Threshold(signal, node.op.value if on_the_left else FLIPPED[node.op.value], value)
