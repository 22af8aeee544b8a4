"""Runs of the optimiser: everything that works on a run directory.

- `directory`, `staging`, `lock`, `records`, `trial_log`: the run directory's layout, files and
  lock (a new one built beside its destination and renamed into place), and the one reader of
  its trial lines;
- `prepare`: a run made ready for its trials (started from a task, or reopened); `resume`: what
  `--resume` checks;
- `recorder`: each finished trial recorded (the trial loop and `tell` alike), and `finish_run`;
- `store`: one protocol for runs on disk and in memory;
- `asktell`: trials handed out to run elsewhere and told back; `targets`: the run `stlopt ask`
  means (a run directory, or a task file's run);
- `workers`: parallel trials in worker processes;
- `sweep_file`, `sweep`: grids of runs, locally or on Ray.
"""
