"""The two robustness semantics as strategies: each says what a conjunction of operands, a
conjunction over sliding windows (`G`; `F` is `!G!`) and an until are, in its kernels. The
compiler asks `Semantics.kernels` and never tests which semantics it has."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from stl_lfd.stl.kernels.conjunction import classic_conjunction, new_conjunction, new_conjunction_of
from stl_lfd.stl.kernels.until import classic_until, new_until
from stl_lfd.stl.kernels.windows import new_windows, window_min


@dataclass(frozen=True)
class ClassicKernels:
    """The classic space robustness: minima and maxima."""

    def conjunction(self, values: np.ndarray) -> np.ndarray:
        """Along the last axis: `... x m` -> `...`."""
        return classic_conjunction(values)

    def conjunction_of(self, operands: list[np.ndarray]) -> np.ndarray:
        """Of arrays of one shape, pairwise."""
        result = operands[0]
        for operand in operands[1:]:
            result = np.minimum(result, operand)
        return result

    def windows(self, values: np.ndarray, width: int, count: int) -> np.ndarray:
        """The conjunction of each of `count` windows of `width` samples: `... x n` -> `... x count`."""
        return window_min(values, width, count)

    def until(self, left: np.ndarray, right: np.ndarray, lo: int, width: int, count: int) -> np.ndarray:
        """`left U[lo, width-1] right` at each of `count` outputs."""
        return classic_until(left, right, lo, width, count)


@dataclass(frozen=True)
class NewKernels:
    """The new robustness of Varnai & Dimarogonas with sharpness `nu`."""

    nu: float

    def conjunction(self, values: np.ndarray) -> np.ndarray:
        return new_conjunction(values, self.nu)

    def conjunction_of(self, operands: list[np.ndarray]) -> np.ndarray:
        return new_conjunction_of(operands, self.nu)

    def windows(self, values: np.ndarray, width: int, count: int) -> np.ndarray:
        return new_windows(values, width, count, self.nu)

    def until(self, left: np.ndarray, right: np.ndarray, lo: int, width: int, count: int) -> np.ndarray:
        return new_until(left, right, lo, width, count, self.nu)


Kernels = ClassicKernels | NewKernels
# The semantics by name: name -> its kernels for a sharpness nu (which only `new` uses).
KERNELS = {"classic": lambda nu: ClassicKernels(), "new": NewKernels}
