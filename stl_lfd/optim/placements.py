"""A trial executed at several placements of the scene's objects: the parts the search methods
model (the spec's, or the spec's at each placement) and the trial's outcome (the worst)."""

from __future__ import annotations

from stl_lfd.optim.methods.base import Composition
from stl_lfd.optim.trials import Outcome
from stl_lfd.poses import Pose
from stl_lfd.stl import SpecParts


def spec_composition(parts: SpecParts) -> Composition:
    """The spec's parts and routes, as the search methods model them."""
    return Composition(tuple(parts.names), parts.semantics, 1, tuple((route.name, route.part) for route in parts.routes))


def placement_composition(parts: SpecParts, placements: tuple[dict[str, Pose], ...]) -> Composition:
    """The spec's parts at each placement, named `placement 2 (holder 0.6,0.25,0.04 yaw 0.3): PART`,
    composed within a placement by the spec's semantics and by the minimum over placements
    (each part at each placement gets its own GP output; no routes)."""
    labels = []
    for index, placement in enumerate(placements):
        poses = ", ".join(f"{name} {','.join(f'{v:g}' for v in pose.position)} yaw {pose.yaw:g}" for name, pose in placement.items())
        labels.append(f"placement {index + 1} ({poses})")
    return Composition(tuple(f"{label}: {part}" for label in labels for part in parts.names), parts.semantics, len(labels))


def worst_outcome(outcomes: list[Outcome], composition: Composition) -> Outcome:
    """One trial's outcome from its `outcomes` at each placement: the worst robustness and
    its signals, and the parts at every placement (named as in `composition`)."""
    if len(outcomes) == 1:
        return outcomes[0]
    worst = min(outcomes, key=lambda outcome: outcome.robustness)
    values = [value for outcome in outcomes for value in outcome.components.values()]
    return Outcome(worst.robustness, worst.payload, dict(zip(composition.names, values)))
