"""The run `stlopt ask` means: a run directory, or the run of a task file (in `out`, default
`runs/<task name>`), started by this first ask or continued by the next ones (`asktell`)."""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from stl_lfd.errors import ConfigError
from stl_lfd.optim.inputs import resolve
from stl_lfd.optim.runs.asktell import Asked, ask, ask_new
from stl_lfd.optim.runs.resume import inputs_record
from stl_lfd.optim.task import Overrides, load_task
from stl_lfd.optim.trials import Trial
from stl_lfd.spelling import spelled


def ask_run(
    target: Path,
    out: Path | None = None,
    given: Overrides = Overrides(),
    on_refused: Callable[[Trial], None] = lambda trial: None,
    robot: str = "",
    learn_progress: Callable[[str], None] = lambda message: None,
) -> tuple[Path, Asked | None]:
    """The next trial (or the one pending on `robot`) of the run `target` names: a run directory,
    which keeps its own settings (only `given.trials` may extend it), or a task file, whose run
    in `out` (default `runs/<task name>`) is created with trial 0 when `out` is empty (`ask_new`,
    with the settings `given` on top) and continued otherwise (checked to be that run). Unsafe
    references become failed trials, passed to `on_refused`.

    Returns:
        the run directory, and the trial handed out (None when the run has all its trials).
    """
    if target.is_dir():
        if out is not None or set(given.given()) - {"trials"}:
            raise ConfigError(f"{target}: a run directory keeps its own settings; only {spelled('trials')} may be given with it")
        return target, ask(target, given.trials, on_refused=on_refused, robot=robot)
    file_task = load_task(target)
    run_dir = out or Path("runs") / file_task.name
    if run_dir.is_dir() and any(run_dir.iterdir()):
        return run_dir, ask(run_dir, given.trials, file_task, given, on_refused=on_refused, robot=robot)
    given, note = given.fitted_to(file_task)
    if note:
        learn_progress(note)
    resolved = resolve(given.applied_to(file_task))
    return run_dir, ask_new(resolved, run_dir, inputs_record(file_task, given, resolved), learn_progress)
