"""What `stlopt optimize` shows on stderr while it runs: a header, one line per trial, a verdict.

With `quiet`, only one line on what runs and the verdict (what `make run` shows), and on a
terminal one self-overwriting line of progress in between (trial k of N, the best so far, the
time spent and the time to go), which leaves nothing behind in pipes or logs.
"""

from __future__ import annotations

import time

from rich.console import Console

from stl_lfd.optim.runs.prepare import PreparedRun
from stl_lfd.optim.runs.recorder import finish_run
from stl_lfd.optim.summary import Summary
from stl_lfd.optim.trials import Trial
from stl_lfd.spelling import spelled


class TrialPrinter:
    """Prints a line per finished trial: number, phase, robustness, best so far, satisfied, time."""

    def __init__(self, prepared: PreparedRun, console: Console | None = None, quiet: bool = False) -> None:
        self.console = console or Console(stderr=True, highlight=False, soft_wrap=True)
        self.quiet = quiet
        task, summary = prepared.task, prepared.summary
        optimizer = task.optimizer
        done = len(prepared.history)
        self.budget = optimizer.trials
        initial = summary.initial_robustness
        if quiet:
            if done >= optimizer.trials:
                doing = f"the run is complete ({done} trials)"
            else:
                doing = f"trials {done + 1} to {optimizer.trials}" if done else f"{optimizer.trials} trials"
                doing += f" of method {optimizer.method}"
            self.console.print(f"{task.name}: {task.spec.name}, {doing} on the {task.backend} backend -> {prepared.run.path}")
            self.done_before, self.finished, self.started, self.best = done, done, time.monotonic(), summary.best_robustness
            if self.console.is_terminal and done < optimizer.trials:
                self.status = self.console.status(self._progress(done), spinner="dots")
                self.status.start()
            return
        self.console.print(
            f"[bold]{task.name}[/]: {task.spec.name}, {task.semantics} robustness, {prepared.space.dimension} parameters, "
            f"{task.backend} backend -> {prepared.run.path}"
        )
        self.console.print(f"unoptimised skill: robustness {initial:+.5f} ({_verdict(initial > 0)})")
        plan = optimizer.phases
        if done >= optimizer.trials:
            self.console.print(plan + f"; the run is complete ({done} trials; raise {spelled('trials')} to extend it)")
            return
        self.console.print(plan + (f"; resuming after trial {done}" if done else ""))
        self.console.print(f"[dim]{'trial':>7} {'phase':>7} {'robustness':>11} {'best':>11} {'satisfied':>9} {'time':>7}[/]")

    status = None  # the self-overwriting progress line (quiet, on a terminal)

    def _progress(self, done: int) -> str:
        """`trial k of N, best ..., elapsed, about ... to go` while trial k = `done` + 1 runs."""
        elapsed = time.monotonic() - self.started
        text = f"trial {done + 1} of {self.budget}" if done < self.budget else f"{self.budget} trials done"
        if self.best is not None:
            text += f", best {self.best:+.5f} ({'satisfied' if self.best > 0 else 'violated'})"
        text += f", {_duration(elapsed)} spent"
        finished = done - self.done_before
        if finished and done < self.budget:
            text += f", about {_duration(elapsed / finished * (self.budget - done))} to go"
        return text

    def trial(self, trial: Trial, best: Trial | None) -> None:
        if self.quiet:
            if self.status is not None:
                self.best = best.robustness if best is not None else None
                self.finished += 1  # counted, not the trial's number: with workers, trials finish out of order
                self.status.update(self._progress(self.finished))
            return
        value = f"{trial.robustness:+.5f}" if trial.robustness is not None else "failed"
        best_value = f"{best.robustness:+.5f}" if best is not None else "-"
        mark = f"{'[green]yes[/]' if trial.satisfied else 'no':>{9 + (len('[green][/]') if trial.satisfied else 0)}}"
        line = f"{trial.trial:>3}/{self.budget:<3} {trial.phase:>7} {value:>11} {best_value:>11} {mark} {trial.wall_seconds:6.2f}s"
        if trial.error:
            line += f"  [red]{trial.error}[/]"
        self.console.print(line)

    def stop(self) -> None:
        """Remove the progress line (before the verdict, or when the run stops early)."""
        if self.status is not None:
            self.status.stop()
            self.status = None

    def done(self, summary: Summary) -> None:
        self.stop()
        best = summary.best_robustness
        if best is None:
            self.console.print("[red]every trial failed[/]")
            return
        self.console.print(
            f"best: trial {summary.best_trial}, robustness {best:+.5f} ({_verdict(summary.satisfied)}; "
            f"unoptimised {summary.initial_robustness:+.5f}); {summary.trials} trials in {summary.wall_seconds:.1f} s"
        )


def finish_printed(prepared: PreparedRun, quiet: bool = False, ray: str | None = None) -> Summary:
    """`finish_run` shown on stderr by a `TrialPrinter` (with `quiet`, no line per trial);
    returns the final summary."""
    printer = TrialPrinter(prepared, quiet=quiet)
    try:
        summary = finish_run(prepared, printer.trial, ray=ray)
    finally:
        printer.stop()
    printer.done(summary)
    return summary


def _verdict(satisfied: bool) -> str:
    return "[green]satisfied[/]" if satisfied else "[yellow]violated[/]"


def _duration(seconds: float) -> str:
    """`42 s`, `3 min 05 s`, `1 h 02 min`."""
    seconds = int(round(seconds))
    if seconds < 60:
        return f"{seconds} s"
    if seconds < 3600:
        return f"{seconds // 60} min {seconds % 60:02d} s"
    return f"{seconds // 3600} h {seconds % 3600 // 60:02d} min"
