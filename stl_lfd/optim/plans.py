"""The references of many candidate points, retrieved together and kept for a while: method
`plan` scores the plans of hundreds of points per proposal, and successive tracking models
score the same recent points again (a point's reference does not depend on the model)."""

from __future__ import annotations

from collections import OrderedDict

import numpy as np

from stl_lfd.hsmm import HSMM
from stl_lfd.optim.space import SearchSpace
from stl_lfd.sim import Reference
from stl_lfd.skill.placed import PlacedSkill

# How much of the references it retrieved a `PlanCache` keeps: method plan's pool of 128
# candidates and its refinement draws, for a task of phi1's size (about 0.3 MB a reference).
PLANNED_REFERENCE_BYTES = 128 * 2**20


class PlanCache:
    """The references of points of `space` applied to `models`, at each of the `placed`
    skills (one per placement), the latest kept up to `PLANNED_REFERENCE_BYTES`."""

    def __init__(self, models: dict[str, HSMM], space: SearchSpace, placed: list[PlacedSkill]) -> None:
        self.models, self.space, self.placed = models, space, placed
        self._references: OrderedDict[bytes, list[Reference]] = OrderedDict()
        self._reference_sizes: dict[bytes, int] = {}  # bytes of each kept point's references

    def references(self, points: np.ndarray, keep: bool = False) -> list[list[Reference]]:
        """The references of `b x d` points at each placement (placement x point), retrieved
        together. With `keep`, those retrieved lately are kept (up to PLANNED_REFERENCE_BYTES,
        the oldest dropped first): the plan scores of successive tracking models share them (a
        point's reference does not depend on the model)."""
        keys = [np.asarray(point, dtype=float).tobytes() for point in points]
        known = self._references if keep else {}
        new = list(dict.fromkeys(key for key in keys if key not in known))
        retrieved: dict[bytes, list[Reference]] = {}
        if new:
            placements = [placed.references([self.space.apply(self.models, np.frombuffer(key)) for key in new]) for placed in self.placed]
            retrieved = {key: [references[index] for references in placements] for index, key in enumerate(new)}
        result = [[(retrieved.get(key) or known[key])[placement] for key in keys] for placement in range(len(self.placed))]
        if keep:
            self._keep(keys, retrieved)
        return result

    def _keep(self, keys: list[bytes], retrieved: dict[bytes, list[Reference]]) -> None:
        """Keep the `retrieved` references and mark `keys` as the latest used."""
        self._references.update(retrieved)
        self._reference_sizes.update({key: sum(reference_bytes(reference) for reference in references) for key, references in retrieved.items()})
        for key in keys:
            self._references.move_to_end(key)
        total = sum(self._reference_sizes.values())
        while total > PLANNED_REFERENCE_BYTES and self._references:
            key, _ = self._references.popitem(last=False)
            total -= self._reference_sizes.pop(key)


def reference_bytes(reference: Reference) -> int:
    """The memory a reference's arrays take."""
    return sum(value.nbytes for value in vars(reference).values() if isinstance(value, np.ndarray))
