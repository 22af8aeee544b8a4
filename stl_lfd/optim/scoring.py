"""Recorded signals scored against a spec: the robustness of each of its top-level parts, and of
the spec (the parts composed), for one recording or many at once."""

from __future__ import annotations

from typing import Sequence

import numpy as np

from stl_lfd.errors import SignalError
from stl_lfd.optim.trials import Outcome
from stl_lfd.signals import SignalTable
from stl_lfd.stl import SpecParts


class Scorer:
    """Scores recordings with the spec's `parts` (payload of each outcome: its recording)."""

    def __init__(self, parts: SpecParts) -> None:
        self.parts = parts

    def score(self, signals: SignalTable) -> Outcome:
        """The robustness of recorded `signals`, and of each of the spec's parts."""
        return self.score_all([signals])[0]

    def score_all(self, recordings: Sequence[SignalTable]) -> list[Outcome]:
        """`score` each of the `recordings`; those on the same sample times as a `B x T` batch."""
        for signals in recordings:
            missing = sorted(self.parts.signals - set(signals.columns))
            if missing:
                raise SignalError(f"{signals.source}: no column {', '.join(missing)}, which the spec needs")
        outcomes: list[Outcome | None] = [None] * len(recordings)
        groups: dict[bytes, list[int]] = {}
        for index, signals in enumerate(recordings):
            groups.setdefault(np.asarray(signals.times).tobytes(), []).append(index)
        for indices in groups.values():
            batch = {name: np.stack([recordings[index].columns[name] for index in indices]) for name in self.parts.signals}
            times = recordings[indices[0]].times
            # The spec is evaluated once, part by part; composing the parts is exactly its robustness.
            values = np.atleast_2d(self.parts(batch, times))
            routes = self.parts.route_values(batch, times)
            for row, index in enumerate(indices):
                outcomes[index] = Outcome(
                    self.parts.compose(values[row]),
                    recordings[index],
                    dict(zip(self.parts.names, values[row].tolist())),
                    {name: float(value[row]) for name, value in routes.items()} or None,
                )
        return outcomes
