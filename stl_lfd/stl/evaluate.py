"""Robustness of a recorded signal file against a specification file (`stlopt robustness`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from stl_lfd.choices import DEFAULT_SEMANTICS
from stl_lfd.errors import SignalError, SpecError
from stl_lfd.signals import SignalTable, read_signal_csv
from stl_lfd.stl import ast
from stl_lfd.stl.components import split_spec
from stl_lfd.stl.parser import load_spec, source_text
from stl_lfd.stl.robustness import compile_spec


@dataclass(frozen=True)
class Evaluation:
    """Result of evaluating one signal file.

    Attributes:
        robustness: value at the first sample (may be +-inf when every window is empty).
        satisfied: robustness > 0.
        parts: when asked for, the robustness of each part of the spec's top-level conjunction
            (its text -> value; the spec itself when it is not a conjunction), of which
            `robustness` is the composition; None otherwise.
    """

    spec: str
    signal: str
    semantics: str
    nu: float | None
    samples: int
    duration: float
    robustness: float
    parts: dict[str, float] | None = None

    @property
    def satisfied(self) -> bool:
        return self.robustness > 0

    def to_json(self) -> dict:
        """A JSON-ready dict; an infinite robustness is written as null (JSON has no infinity)."""
        parts = {} if self.parts is None else {"parts": {name: _finite_or_none(value) for name, value in self.parts.items()}}
        return {
            "robustness": _finite_or_none(self.robustness),
            "satisfied": self.satisfied,
            **parts,
            "semantics": self.semantics,
            "nu": self.nu,
            "samples": self.samples,
            "duration": self.duration,
            "spec": self.spec,
            "signal": self.signal,
        }


def evaluate_file(spec_path: str | Path, signal_path: str | Path, semantics: str = DEFAULT_SEMANTICS, nu: float = 1.0, parts: bool = False) -> Evaluation:
    """Load, compile and evaluate (with `parts`, each part of the spec too); raises
    `StlLfdError` subclasses on bad input."""
    spec = load_spec(spec_path)  # a bad spec is reported before a bad signal file
    table = read_signal_csv(signal_path)
    evaluation = _evaluate(spec, spec_path, table, semantics, nu)
    return replace(evaluation, parts=_part_values(spec, spec_path, table, semantics, nu)) if parts else evaluation


def evaluate_table(spec_path: str | Path, table: SignalTable, semantics: str = DEFAULT_SEMANTICS, nu: float = 1.0) -> Evaluation:
    """Robustness of an in-memory signal table against a specification file."""
    return _evaluate(load_spec(spec_path), spec_path, table, semantics, nu)


def _evaluate(spec: ast.Spec, spec_path: str | Path, table: SignalTable, semantics: str, nu: float) -> Evaluation:
    function = compile_spec(spec, semantics, nu, source=str(spec_path))
    try:
        value = function(table.columns, table.times)
    except SpecError as error:
        raise error.located(error.source, source_text(error.source)) from None
    except SignalError as error:
        raise SignalError(f"{table.source}: {error}") from None
    return Evaluation(
        spec=str(spec_path),
        signal=table.source,
        semantics=semantics,
        nu=nu if semantics == "new" else None,
        samples=table.samples,
        duration=table.duration,
        robustness=value,
    )


def _part_values(spec: ast.Spec, spec_path: str | Path, table: SignalTable, semantics: str, nu: float) -> dict[str, float]:
    """The robustness of each part of the spec's top-level conjunction (`split_spec`)."""
    parts = split_spec(spec, semantics, nu, source=str(spec_path))
    values = np.atleast_1d(parts(table.columns, table.times))
    return dict(zip(parts.names, values.tolist()))


def _finite_or_none(value: float) -> float | None:
    return value if math.isfinite(value) else None
