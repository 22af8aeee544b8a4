"""Which robustness to compute: `Semantics`, the classic space robustness or the new one of
Varnai & Dimarogonas with sharpness `nu`, and its kernels (`stl_lfd.stl.kernels.semantics`)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Literal

from stl_lfd.choices import SEMANTICS
from stl_lfd.errors import SpecError
from stl_lfd.stl.kernels.semantics import KERNELS, Kernels

SemanticsName = Literal["classic", "new"]


@dataclass(frozen=True)
class Semantics:
    """Which robustness to compute: `classic` space robustness or `new` with sharpness `nu`."""

    name: SemanticsName = "classic"
    nu: float = 1.0

    def __post_init__(self) -> None:
        if self.name not in SEMANTICS:
            raise SpecError(f"unknown semantics '{self.name}'; choose one of {', '.join(SEMANTICS)}")
        if not (math.isfinite(self.nu) and self.nu > 0):
            raise SpecError(f"nu must be a positive number (got {self.nu})")

    @cached_property
    def kernels(self) -> Kernels:
        """What a conjunction, a window and an until are under this semantics (made once: the
        evaluators ask for them at every node they evaluate)."""
        return KERNELS[self.name](self.nu)
