"""A fold over a directed acyclic graph without recursion, so that deep inputs (formulas nested
hundreds of levels, YAML aliases of aliases) cannot exhaust the stack. Nodes shared by several
parents are folded once."""

from __future__ import annotations

from typing import Callable, Sequence, TypeVar

Node = TypeVar("Node")


def fold(root: Node, children: Callable[[Node], Sequence[Node]], combine: Callable[[Node, list[int]], int]) -> int:
    """`combine(node, [value of each child])` for `root`, children first (post-order).

    The graph must be acyclic; nodes are told apart by identity.
    """
    values: dict[int, int] = {}
    stack: list[tuple[Node, bool]] = [(root, False)]
    while stack:
        node, expanded = stack.pop()
        below = children(node)
        if expanded:
            values[id(node)] = combine(node, [values[id(child)] for child in below])
        elif id(node) not in values:
            stack.append((node, True))
            stack.extend((child, False) for child in below if id(child) not in values)
    return values[id(root)]
