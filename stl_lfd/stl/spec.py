"""`Spec`: a parsed specification with its robustness, the one object a script needs.

    >>> from stl_lfd.stl import Spec
    >>> spec = Spec.parse("F[0, 1] x > 0.5 & G x < 2")
    >>> spec.robustness({"x": [0.0, 0.2, 0.9]}, times=[0.0, 0.5, 1.0], semantics="classic")
    0.4
    >>> spec.components({"x": [0.0, 0.2, 0.9]}, times=[0.0, 0.5, 1.0], semantics="classic")
    {'F[0, 1] x > 0.5': 0.4, 'G x < 2': 1.1}

Compiled functions are kept per (semantics, nu), so calling `robustness` in a loop compiles
once.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np
from numpy.typing import ArrayLike

from stl_lfd.choices import DEFAULT_SEMANTICS
from stl_lfd.stl import ast
from stl_lfd.stl.components import SpecParts, split_spec
from stl_lfd.stl.parser import load_spec, parse
from stl_lfd.stl.printer import format_spec
from stl_lfd.stl.robustness import Robustness, compile_spec
from stl_lfd.stl.semantics import SemanticsName


@dataclass(frozen=True)
class Spec:
    """A specification.

    Attributes:
        tree: the typed syntax tree (`ast.Spec`).
        source: the file it came from, or `<string>`.
    """

    tree: ast.Spec
    source: str = "<string>"
    _compiled: dict[tuple[Any, ...], Any] = field(default_factory=dict, compare=False, repr=False)

    @classmethod
    def parse(cls, text: str, source: str = "<string>") -> "Spec":
        """Parse STL text (definitions `name := formula`, the last one the specification)."""
        return cls(parse(text, source), source)

    @classmethod
    def load(cls, path: str | Path) -> "Spec":
        """Read and parse a `.stl` file (its `include`s relative to it)."""
        return cls(load_spec(path), str(path))

    @property
    def signals(self) -> frozenset[str]:
        """The signal names the formula reads."""
        return self.function("classic").signals

    def function(self, semantics: SemanticsName = DEFAULT_SEMANTICS, nu: float = 1.0) -> Robustness:
        """The compiled robustness function (see `stl_lfd.stl.robustness.Robustness`)."""
        key = ("function", semantics, nu)
        if key not in self._compiled:
            self._compiled[key] = compile_spec(self.tree, semantics, nu, self.source)
        return self._compiled[key]

    def parts(self, semantics: SemanticsName = DEFAULT_SEMANTICS, nu: float = 1.0) -> SpecParts:
        """The top-level conjuncts and their composition, as the optimiser models them."""
        key = ("parts", semantics, nu)
        if key not in self._compiled:
            self._compiled[key] = split_spec(self.tree, semantics, nu, self.source)
        return self._compiled[key]

    def robustness(
        self, signals: Mapping[str, ArrayLike], times: ArrayLike, semantics: SemanticsName = DEFAULT_SEMANTICS, nu: float = 1.0
    ) -> float | np.ndarray:
        """Robustness at the first sample: a float, or `B` values for `B x T` signal arrays.

        Args:
            signals: name -> `T` (or `B x T`) samples; a `SignalTable`'s `columns` fits.
            times: `T` uniformly spaced sample times in seconds.
        """
        return self.function(semantics, nu)(signals, times)

    def trace(self, signals: Mapping[str, ArrayLike], times: ArrayLike, semantics: SemanticsName = DEFAULT_SEMANTICS, nu: float = 1.0) -> np.ndarray:
        """The robustness signal at every sample: `T` (or `B x T`)."""
        return self.function(semantics, nu).trace(signals, times)

    def components(self, signals: Mapping[str, ArrayLike], times: ArrayLike, semantics: SemanticsName = DEFAULT_SEMANTICS, nu: float = 1.0) -> dict[str, float]:
        """The robustness of each top-level conjunct by its text (one trace, not a batch)."""
        parts = self.parts(semantics, nu)
        return dict(zip(parts.names, np.asarray(parts(signals, times), dtype=float).tolist()))

    def __str__(self) -> str:
        return format_spec(self.tree)
