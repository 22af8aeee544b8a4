"""Optimisation of skill parameters for STL specifications (the paper's Algorithm 1).

- `task`: task files (YAML) and their validation;
- `space`: which parameters move, their bounds, and how a point becomes a model;
- `acquisition`: Sobol and random points, GP fitting and acquisition maximisation (BoTorch);
- `loop`: the trial loop;
- `rundir`: run directories;
- `run`: a run from a task file, from preparation to summary.
"""

from stl_lfd.optim.loop import Trial, best_trial
from stl_lfd.optim.run import optimise, resume_run, start_run
from stl_lfd.optim.rundir import RunDirectory, trial_skill
from stl_lfd.optim.space import ParameterSpace, SearchSpace, build_search_space, build_space
from stl_lfd.optim.task import SINGLE_SKILL, Task, load_task

__all__ = [
    "SINGLE_SKILL",
    "ParameterSpace",
    "SearchSpace",
    "RunDirectory",
    "Task",
    "Trial",
    "best_trial",
    "build_search_space",
    "build_space",
    "load_task",
    "optimise",
    "resume_run",
    "start_run",
    "trial_skill",
]
