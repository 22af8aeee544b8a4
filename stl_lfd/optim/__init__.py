"""Optimisation of skill parameters for STL specifications (the paper's Algorithm 1).

    task.py, settings.py                 what to optimise and how: task files, `Parameters`,
                                         `Optimizer`, command-line `Overrides`
    inputs.py                            a task's files read once (`TaskInputs`), its skills
    space.py, features.py                the parameters that move, their bounds; what a GP sees
    objective.py                         a point -> adapted skill -> rollout -> robustness of parts
    scoring.py, plans.py, placements.py  the objective's pieces: signals scored by the spec's
                                         parts; many points' references, kept a while; a trial
                                         at several placements of the objects
    trials.py                            `Trial`, `Outcome`, and the observations methods learn from
    loop.py                              the thin loop: ask the method for a batch, execute, record
    tracking_fit.py                      the tracking and grasp models fitted on a run's executions
    methods/                             one class per search method (plan, stl, pi, logei, random)
                                         behind `SearchMethod.propose(request)`, found by name
    runs/                                run directories, start and resume, recording, ask/tell,
                                         parallel workers, sweeps
    api.py                               `optimize` from Python objects, in memory

Names are loaded on first use, so that importing `stl_lfd.optim.task` (for the method names,
say) does not load the whole optimiser.
"""

from __future__ import annotations

from stl_lfd.lazy import lazy_exports

_HOMES = {
    "Trial": "stl_lfd.optim.trials",
    "Outcome": "stl_lfd.optim.trials",
    "best_trial": "stl_lfd.optim.trials",
    "finish_run": "stl_lfd.optim.runs.recorder",
    "open_run": "stl_lfd.optim.runs.prepare",
    "resume_run": "stl_lfd.optim.runs.prepare",
    "start_run": "stl_lfd.optim.runs.prepare",
    "RunDirectory": "stl_lfd.optim.runs.directory",
    "trial_skill": "stl_lfd.optim.runs.replay",
    "ParameterSpace": "stl_lfd.optim.space",
    "SearchSpace": "stl_lfd.optim.space",
    "build_search_space": "stl_lfd.optim.space",
    "build_space": "stl_lfd.optim.space",
    "SINGLE_SKILL": "stl_lfd.optim.settings",
    "Optimizer": "stl_lfd.optim.settings",
    "Parameters": "stl_lfd.optim.settings",
    "Overrides": "stl_lfd.optim.task",
    "Task": "stl_lfd.optim.task",
    "load_task": "stl_lfd.optim.task",
    "optimize": "stl_lfd.optim.api",
    "Result": "stl_lfd.optim.api",
    "TaskInputs": "stl_lfd.optim.inputs",
    "resolve": "stl_lfd.optim.inputs",
    "spec_parts": "stl_lfd.optim.inputs",
    "task_models": "stl_lfd.optim.inputs",
    "SkillObjective": "stl_lfd.optim.objective",
    "objective_for": "stl_lfd.optim.objective",
    "ObjectiveFactory": "stl_lfd.optim.runs.workers",
    "RayPool": "stl_lfd.optim.runs.ray_workers",
    "local_map": "stl_lfd.optim.runs.sweep",
}

__all__, __getattr__, __dir__ = lazy_exports("stl_lfd.optim", _HOMES, globals())
