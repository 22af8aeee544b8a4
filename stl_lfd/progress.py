"""What `stlopt optimize` shows on stderr while it runs: a header, one line per trial, a verdict.

With `quiet`, only one line on what runs and the verdict (what `make run` shows).
"""

from __future__ import annotations

from rich.console import Console

from stl_lfd.optim.runs.prepare import PreparedRun
from stl_lfd.optim.summary import Summary
from stl_lfd.optim.trials import Trial


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
            return
        self.console.print(
            f"[bold]{task.name}[/]: {task.spec.name}, {task.semantics} robustness, {prepared.space.dimension} parameters, "
            f"{task.backend} backend -> {prepared.run.path}"
        )
        self.console.print(f"unoptimised skill: robustness {initial:+.5f} ({_verdict(initial > 0)})")
        plan = optimizer.phases
        if done >= optimizer.trials:
            self.console.print(plan + f"; the run is complete ({done} trials; raise --iterations to extend it)")
            return
        self.console.print(plan + (f"; resuming after trial {done}" if done else ""))
        self.console.print(f"[dim]{'trial':>7} {'phase':>7} {'robustness':>11} {'best':>11} {'satisfied':>9} {'time':>7}[/]")

    def trial(self, trial: Trial, best: Trial | None) -> None:
        if self.quiet:
            return
        value = f"{trial.robustness:+.5f}" if trial.robustness is not None else "failed"
        best_value = f"{best.robustness:+.5f}" if best is not None else "-"
        mark = f"{'[green]yes[/]' if trial.satisfied else 'no':>{9 + (len('[green][/]') if trial.satisfied else 0)}}"
        line = f"{trial.trial:>3}/{self.budget:<3} {trial.phase:>7} {value:>11} {best_value:>11} {mark} {trial.wall_seconds:6.2f}s"
        if trial.error:
            line += f"  [red]{trial.error}[/]"
        self.console.print(line)

    def done(self, summary: Summary) -> None:
        best = summary.best_robustness
        if best is None:
            self.console.print("[red]every trial failed[/]")
            return
        self.console.print(
            f"best: trial {summary.best_trial}, robustness {best:+.5f} ({_verdict(summary.satisfied)}; "
            f"unoptimised {summary.initial_robustness:+.5f}); {summary.trials} trials in {summary.wall_seconds:.1f} s"
        )


def _verdict(satisfied: bool) -> str:
    return "[green]satisfied[/]" if satisfied else "[yellow]violated[/]"
