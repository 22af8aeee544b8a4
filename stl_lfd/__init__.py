"""stlopt: adapt demonstrated robot skills to Signal Temporal Logic requirements.

The public API, loaded on first use (so `import stl_lfd` loads neither torch nor pybullet):

- STL: `Spec` (`Spec.parse`, `Spec.load`, `.robustness`, `.trace`, `.components`), `compile_spec`;
- signals: `SignalTable`, `read_signal_csv`, `write_signal_csv`;
- skills: `HSMM` (`fit`, `predict`, `sample`), `TPHSMM` (`at(poses)`), `Pose`, `learn`,
  `learn_from_folder`, `load_model`, `save_model`, `retrieve`; `load_scene`, `execute`,
  `rollout_model`; `Command` (an external executor, for
  `backend="command"`), `read_reference_csv`;
- optimisation: `optimize` -> `Result`, with `Parameters`, `MeanParameters`,
  `DurationParameters` and `Optimizer`; `load_task` for task files;
- how a robot tracks: `TrackingModel` (`fit` on `Execution`s, `predict`), `GraspModel` (where
  a carried object sits in the hand, `fit` on recorded signals), `read_tracking` (a run's
  `tracking.json`).
"""

from __future__ import annotations

from stl_lfd.lazy import lazy_exports

__version__ = "0.1.0"

_HOMES = {
    "Spec": "stl_lfd.stl",
    "compile_spec": "stl_lfd.stl",
    "SignalTable": "stl_lfd.signals",
    "read_signal_csv": "stl_lfd.signals",
    "write_signal_csv": "stl_lfd.signals",
    "HSMM": "stl_lfd.hsmm",
    "TPHSMM": "stl_lfd.hsmm",
    "Pose": "stl_lfd.poses",
    "learn": "stl_lfd.hsmm",
    "learn_from_folder": "stl_lfd.hsmm",
    "load_model": "stl_lfd.hsmm",
    "save_model": "stl_lfd.hsmm",
    "retrieve": "stl_lfd.hsmm",
    "load_scene": "stl_lfd.sim.scene_file",
    "execute": "stl_lfd.sim",
    "Command": "stl_lfd.sim.executor",
    "read_reference_csv": "stl_lfd.sim.reference",
    "rollout_model": "stl_lfd.skill",
    "optimize": "stl_lfd.optim.api",
    "Result": "stl_lfd.optim.api",
    "Parameters": "stl_lfd.optim.settings",
    "MeanParameters": "stl_lfd.optim.settings",
    "DurationParameters": "stl_lfd.optim.settings",
    "Optimizer": "stl_lfd.optim.settings",
    "load_task": "stl_lfd.optim.task",
    "TrackingModel": "stl_lfd.sim.tracking_model",
    "Execution": "stl_lfd.sim.tracking_model",
    "GraspModel": "stl_lfd.sim.grasp_model",
    "read_tracking": "stl_lfd.optim.tracking_fit",
    "QUATERNION_COLUMNS": "stl_lfd.rotations",
    "keep_freed_memory": "stl_lfd.allocator",
}

__all__, __getattr__, __dir__ = lazy_exports("stl_lfd", _HOMES, globals())
