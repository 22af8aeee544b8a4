"""Optimisation of skill parameters for STL specifications (the paper's Algorithm 1).

- `task`: task files (YAML), the optimiser's settings and their validation;
- `space`: which parameters move, their bounds, and how a point becomes a model;
- `acquisition`: Sobol and random points, GP fitting and acquisition maximisation (BoTorch);
- `composite`: method `stl`, one GP output per part of the spec;
- `planned`: method `plan`, the same with each part's plan (its reference scored as the
  kinematic backend executes it) as the prior;
- `features`: what method `stl`'s GP sees of a point (the state path it selects, the means on
  it and when each of its states starts);
- `loop`: the trial loop;
- `rundir`, `resume`: run directories, and what a resume checks;
- `run`: a run from a task file, from preparation to summary;
- `api`: `optimize` from Python objects, in memory.

Names are loaded on first use, so that importing `stl_lfd.optim.task` (for the method names,
say) does not load the whole optimiser.
"""

from __future__ import annotations

from stl_lfd.lazy import lazy_exports

_HOMES = {
    "Trial": "stl_lfd.optim.loop",
    "best_trial": "stl_lfd.optim.loop",
    "optimise": "stl_lfd.optim.run",
    "resume_run": "stl_lfd.optim.run",
    "start_run": "stl_lfd.optim.run",
    "RunDirectory": "stl_lfd.optim.rundir",
    "trial_skill": "stl_lfd.optim.rundir",
    "ParameterSpace": "stl_lfd.optim.space",
    "SearchSpace": "stl_lfd.optim.space",
    "build_search_space": "stl_lfd.optim.space",
    "build_space": "stl_lfd.optim.space",
    "SINGLE_SKILL": "stl_lfd.optim.task",
    "Task": "stl_lfd.optim.task",
    "load_task": "stl_lfd.optim.task",
    "optimize": "stl_lfd.optim.api",
    "Result": "stl_lfd.optim.api",
}

__all__, __getattr__, __dir__ = lazy_exports("stl_lfd.optim", _HOMES, globals())
