"""`PlacedSkill`: skills (one model, or a behaviour's) in a scene whose objects stand at one
placement, turned into a reference (by `stl_lfd.skill.reference`) and executed: how `stlopt
rollout`, `stlopt replay` and the optimiser's objective execute a skill."""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable, Mapping, Sequence

from stl_lfd.hsmm import HSMM
from stl_lfd.poses import Pose
from stl_lfd.sim import DEFAULT_RATE, Backend, Reference, Rollout, Scene, execute, load_scene
from stl_lfd.sim.scene_file import placement_from_options
from stl_lfd.skill.behaviour import Behaviour, load_skill
from stl_lfd.skill.reference import build_references

DEFAULT_SCENE = "free_space"


@dataclass(frozen=True)
class PlacedSkill:
    """Skills to execute in a placed scene.

    Attributes:
        models: skill name -> model (`skill` for a single model).
        behaviour: the behaviour that sequences them, or None for a single model.
        scene: the scene, its objects at their placement.
        duration: seconds to execute (None: the skill's expected duration).
    """

    models: dict[str, HSMM]
    behaviour: Behaviour | None
    scene: Scene
    duration: float | None = None

    @classmethod
    def load(
        cls, path: str | Path, scene: str | Scene | None = None, placement: Mapping[str, Pose] | Sequence[str] = (), duration: float | None = None
    ) -> "PlacedSkill":
        """The skills of a model or behaviour file, in `scene` (default: the behaviour's, or
        free space) at `placement` (frame -> pose, or `--place` texts `NAME=x,y[,z[,yaw]]`)."""
        models, behaviour = load_skill(path)
        return cls(models, behaviour, placed_scene(scene or (behaviour.scene if behaviour is not None else DEFAULT_SCENE), placement), duration)

    def with_models(self, models: dict[str, HSMM]) -> "PlacedSkill":
        """The same skills with other models (an adapted skill)."""
        return replace(self, models=models)

    def reference(self) -> Reference:
        """What executing the skills means: the behaviour's (or the single skill's) reference,
        for the poses of the scene's object frames."""
        return self.references([self.models])[0]

    def references(self, models: Sequence[dict[str, HSMM]]) -> list[Reference]:
        """`reference` of N sets of models (the skills with other parameters), retrieved together."""
        return build_references(models, self.behaviour, self.scene.gripper_opening, self.duration, self.scene.frame_poses)

    def execute(self, backend: str | Backend, rate: float = DEFAULT_RATE, observer: Callable | None = None, reference: Reference | None = None) -> Rollout:
        """Execute the skills (or their `reference`, if already retrieved) on `backend`."""
        return execute(self.reference() if reference is None else reference, self.scene, backend, rate, observer)


def placed_scene(scene: str | Scene, placement: Mapping[str, Pose] | Sequence[str] = (), source: str | None = None) -> Scene:
    """`scene` (a name, a scene file or a `Scene`) with its object frames at `placement`: frame
    -> pose, or `--place` texts `NAME=x,y[,z[,yaw]]` (parsed and checked against the scene)."""
    world = load_scene(scene) if not isinstance(scene, Scene) else scene
    if not isinstance(placement, Mapping):
        placement = placement_from_options(world, list(placement))
    return world.place(placement, source) if placement else world
