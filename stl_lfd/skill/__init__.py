"""Skills in execution: a skill model (or a behaviour of several skills with gripper actions)
turned into a reference trajectory and executed in a scene. The glue of `stl_lfd.hsmm` and
`stl_lfd.sim`, shared by `rollout`, `replay` and the optimiser.

- `execution`: one model -> reference -> rollout;
- `behaviour`: behaviour files, and the joined reference of their skills.
"""

from stl_lfd.skill.behaviour import Behaviour, behaviour_models, load_behaviour, reference_for
from stl_lfd.skill.execution import reference_of, rollout_model, scene_with_spec_regions

__all__ = ["Behaviour", "behaviour_models", "load_behaviour", "reference_for", "reference_of", "rollout_model", "scene_with_spec_regions"]
