"""Skills in execution: a skill model (or a behaviour of several skills with gripper actions)
turned into a reference trajectory and executed in a scene. The glue of `stl_lfd.hsmm` and
`stl_lfd.sim`, shared by `rollout`, `replay` and the optimiser.

- `reference`: the one way skills become a reference: a model, or a behaviour's skills joined
  with its gripper actions, for N sets of parameters at once;
- `execution`: one model executed in a scene; `timed_rollout`, placed skills executed once on a
  backend of their own;
- `behaviour`: behaviour files, and `load_skill` for a model or behaviour file;
- `placed`: `PlacedSkill`, skills in a scene at one placement of its objects, executed the same
  way by every command.
"""

from stl_lfd.skill.behaviour import Behaviour, behaviour_models, load_behaviour, load_skill
from stl_lfd.skill.execution import rollout_model, scene_with_spec_regions, timed_rollout
from stl_lfd.skill.placed import PlacedSkill, placed_scene
from stl_lfd.skill.reference import build_reference, build_references

__all__ = [
    "Behaviour",
    "PlacedSkill",
    "behaviour_models",
    "load_behaviour",
    "load_skill",
    "placed_scene",
    "build_reference",
    "build_references",
    "rollout_model",
    "scene_with_spec_regions",
    "timed_rollout",
]
