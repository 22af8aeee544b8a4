"""`stlopt robustness`: the robustness of a recorded signal."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import typer

from stl_lfd.choices import DEFAULT_SEMANTICS
from stl_lfd.cli.options import SemanticsOption
from stl_lfd.cli.program import PlainUsage, app, one_blas_thread, user_errors


@app.command(cls=PlainUsage)
def robustness(
    spec: Path = typer.Argument(..., metavar="SPEC", help="STL specification file (.stl)."),
    signal_csv: str = typer.Argument(..., metavar="SIGNAL_CSV", help="Signal CSV with a time column t; '-' reads stdin."),
    semantics: SemanticsOption = typer.Option(SemanticsOption(DEFAULT_SEMANTICS), help="The paper's new robustness, or the classic space robustness."),
    nu: float = typer.Option(1.0, help="Sharpness of the new robustness (> 0); larger is closer to classic."),
    as_json: bool = typer.Option(False, "--json", help="Print one JSON object instead of the bare number."),
    parts: bool = typer.Option(False, "--parts", help="Also print each part of the spec's top-level conjunction: its robustness and its text."),
) -> None:
    """Print the robustness of a recorded signal with respect to a specification.

    The robustness is the value at the first sample; it is positive exactly when the signal
    satisfies the specification. Without --json, stdout gets the number and stderr a verdict
    naming the semantics. The default is the paper's new robustness, as 'stlopt optimize'
    scores with; --semantics classic gives the space robustness (the verdicts agree).
    --parts adds a line per part of the spec's top-level conjunction (its robustness, a tab,
    its text): which part fails, and by how much in its own units.

    Example:

    \b
        stlopt robustness specs/example.stl examples/s1.csv --semantics new --json
    """
    one_blas_thread()
    from stl_lfd.stl.evaluate import evaluate_file

    with user_errors():
        result = evaluate_file(spec, signal_csv, semantics.value, nu, parts=parts)
    if as_json:
        print(json.dumps(result.to_json()))
    else:
        print(f"{result.robustness:.10g}")
        for name, value in (result.parts or {}).items():
            print(f"{value:.10g}\t{name}")
        which = "classic robustness" if semantics is SemanticsOption.classic else f"new robustness, nu = {nu:g}"
        print(f"{'satisfied' if result.satisfied else 'violated'} ({which})", file=sys.stderr)
