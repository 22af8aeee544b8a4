"""Boxes described by region definitions such as `L1 := x in [..] & y in [..] & z in [..]`."""

from __future__ import annotations

from stl_lfd.stl import ast

Box = dict[str, tuple[float, float]]


def region_boxes(spec: ast.Spec) -> dict[str, Box]:
    """Definitions that are a single range or a conjunction of ranges over distinct signals.

    Returns:
        definition name -> {signal name -> (lo, hi)}, in definition order.
    """
    boxes: dict[str, Box] = {}
    for definition in spec.definitions:
        box = _box(definition.formula)
        if box is not None:
            boxes[definition.name] = box
    return boxes


def _box(formula: ast.Formula) -> Box | None:
    operands = formula.operands if isinstance(formula, ast.And) else (formula,)
    box: Box = {}
    for operand in operands:
        if not (isinstance(operand, ast.InRange) and isinstance(operand.expr, ast.Signal)):
            return None
        if operand.expr.name in box:
            return None
        box[operand.expr.name] = (operand.lo, operand.hi)
    return box
