"""Skills in execution: a skill model (or a behaviour of several skills with gripper actions)
turned into a reference trajectory and executed in a scene. The glue of `stl_lfd.hsmm` and
`stl_lfd.sim`, shared by `rollout`, `replay` and the optimiser.

- `execution`: one model -> reference -> rollout;
- `behaviour`: behaviour files, the joined reference of their skills, and `load_skill` for a
  model or behaviour file;
- `placed`: `PlacedSkill`, skills in a scene at one placement of its objects, executed the same
  way by every command.
"""

from stl_lfd.skill.behaviour import Behaviour, behaviour_models, load_behaviour, load_skill, reference_for
from stl_lfd.skill.execution import reference_of, rollout_model, scene_with_spec_regions
from stl_lfd.skill.placed import PlacedSkill, placed_scene

__all__ = [
    "Behaviour",
    "PlacedSkill",
    "behaviour_models",
    "load_behaviour",
    "load_skill",
    "placed_scene",
    "reference_for",
    "reference_of",
    "rollout_model",
    "scene_with_spec_regions",
]
