"""The command line: output on stdout, messages on stderr, exit codes, help for every command."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.core import TyperGroup
from typer.main import get_command
from typer.testing import CliRunner

from stl_lfd.cli import app
from tests.conftest import ROOT

runner = CliRunner()
EXAMPLE = str(ROOT / "specs" / "example.stl")
S1, S2 = str(ROOT / "examples" / "s1.csv"), str(ROOT / "examples" / "s2.csv")
THREE_REGIONS = str(ROOT / "examples" / "three_regions.csv")


def invoke(*args: str, stdin: str | None = None):
    return runner.invoke(app, list(args), input=stdin)


def test_every_command_has_help():
    command = get_command(app)
    assert isinstance(command, TyperGroup)
    for name, subcommand in command.commands.items():
        assert subcommand.help and len(subcommand.help) > 40, name
        result = invoke(name, "--help")
        assert result.exit_code == 0 and "Usage" in result.stdout


def test_robustness_reproduces_the_papers_example():
    satisfied = invoke("robustness", EXAMPLE, S1, "--semantics", "classic")
    assert satisfied.exit_code == 0
    assert float(satisfied.stdout) == pytest.approx(0.1)
    assert satisfied.stderr.strip() == "satisfied (classic robustness)"
    violated = invoke("robustness", EXAMPLE, S2, "--semantics", "classic")
    assert float(violated.stdout) == pytest.approx(-0.05)
    assert violated.stderr.strip() == "violated (classic robustness)"


def test_robustness_json_and_stdin():
    result = invoke("robustness", EXAMPLE, "-", "--semantics", "new", "--nu", "2", "--json", stdin=Path(S1).read_text())
    assert result.exit_code == 0
    report = json.loads(result.stdout)
    assert report["satisfied"] is True and report["semantics"] == "new" and report["nu"] == 2.0
    assert report["samples"] == 851 and 0 < report["robustness"] < 0.2


@pytest.mark.parametrize("spec", ["phi1", "phi2"])
def test_demonstrated_path_violates_phi1_and_phi2(spec):
    for semantics in ("classic", "new"):
        result = invoke("robustness", str(ROOT / "specs" / f"{spec}.stl"), THREE_REGIONS, "--semantics", semantics, "--json")
        assert json.loads(result.stdout)["satisfied"] is False


@pytest.mark.parametrize(
    "text, message",
    [
        ("phi := F[1, 2 s > 0\n", "spec.stl:1:15: unexpected 's'"),
        ("phi := F q > 0\n", "spec.stl:1:10: unknown signal 'q' (the trace has: s)"),
        ("phi := F B\n", "spec.stl:1:10: undefined formula 'B'"),
        ("A := F B\nB := G A\n", "spec.stl:1:1: recursive definition: A -> B -> A"),
        ("phi := F[5, 2] s > 0\n", "spec.stl:1:10: empty interval [5, 2]"),
        ("phi := G[-1, 2] s > 0\n", "spec.stl:1:10: interval bounds must be non-negative"),
    ],
)
def test_spec_errors_through_the_cli(tmp_path: Path, text, message):
    spec = tmp_path / "spec.stl"
    spec.write_text(text)
    result = invoke("robustness", str(spec), S1)
    assert result.exit_code == 3
    assert result.stdout == ""
    first, source_line, caret = result.stderr.splitlines()
    assert first.startswith("error: ") and message in first
    assert source_line.strip() == text.splitlines()[int(first.split(":")[2]) - 1].strip()
    assert caret.strip() == "^"
    assert "Traceback" not in result.stderr


def test_signal_errors_through_the_cli(tmp_path: Path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t,s\n0,0.1\n1,nan\n")
    result = invoke("robustness", EXAMPLE, str(bad))
    assert result.exit_code == 4
    assert result.stderr.strip() == f"error: {bad}:3: column 's' is nan"
    missing = invoke("robustness", EXAMPLE, str(tmp_path / "none.csv"))
    assert missing.exit_code == 4 and "no such CSV file" in missing.stderr


def test_bad_options_are_usage_errors():
    assert invoke("robustness", EXAMPLE, S1, "--semantics", "fuzzy").exit_code == 2
    result = invoke("robustness", EXAMPLE, S1, "--semantics", "new", "--nu", "-1")
    assert result.exit_code == 3 and "nu must be a positive number" in result.stderr


def test_horizon_warning_goes_to_stderr(tmp_path: Path):
    spec = tmp_path / "long.stl"
    spec.write_text("phi := G[0, 30] s > 0\n")
    result = invoke("robustness", str(spec), S1)
    assert result.exit_code == 0
    assert "warning:" in result.stderr and "looks 30 s ahead" in result.stderr


def test_help_fits_80_columns_with_whole_examples_and_plain_types():
    command = get_command(app)
    for name, subcommand in command.commands.items():
        result = runner.invoke(app, [name, "--help"], env={"COLUMNS": "80"}, terminal_width=80, prog_name="stlopt")
        assert result.exit_code == 0
        lines = result.stdout.splitlines()
        assert all(len(line) <= 80 for line in lines), name
        assert lines[0].startswith(f"Usage: stlopt {name} [OPTIONS] ") and "{" not in lines[0], lines[0]
        assert "<bool>" not in result.stdout
        docstring_examples = [line.strip() for line in (subcommand.help or "").splitlines() if line.strip().startswith("stlopt ")]
        assert docstring_examples, name
        for example in docstring_examples:
            assert any(line.strip() == example for line in lines), f"{name}: example split: {example}"


@pytest.mark.parametrize("chosen, expected", [(None, 1), ("2", 2)])
def test_robustness_loads_numpy_with_one_blas_thread_unless_the_user_chose(chosen, expected):
    # the command's own start: `_one_blas_thread` runs before the evaluation loads numpy
    code = (
        "import stl_lfd.cli.program as program; program.one_blas_thread(); import numpy, threadpoolctl; "
        "print(max(pool['num_threads'] for pool in threadpoolctl.threadpool_info() if pool['internal_api'] == 'openblas'))"
    )
    env = {name: value for name, value in os.environ.items() if name != "OPENBLAS_NUM_THREADS"} | ({"OPENBLAS_NUM_THREADS": chosen} if chosen else {})
    printed = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True, env=env).stdout
    assert int(printed) == expected


def test_messages_name_options_as_typed_while_a_command_runs_and_settings_otherwise():
    from stl_lfd.spelling import spelled

    result = runner.invoke(app, ["optimize"])
    assert result.exit_code == 5 and "or --spec SPEC" in result.stderr
    assert spelled("spec") == "'spec'" and spelled("trials") == "'trials'"  # the Python API's names again afterwards
    assert _lower_module_lines() == []


def _lower_module_lines() -> list[str]:
    """Strings (not docstrings) of the modules below the CLI that hold an option's spelling; a
    whole command suggested to the user (`stlopt replay RUN --trial 3`) is the CLI's text."""
    import ast
    import re

    found = []
    for path in (ROOT / "stl_lfd").rglob("*.py"):
        if "cli" in path.relative_to(ROOT / "stl_lfd").parts:
            continue
        tree = ast.parse(path.read_text())
        docstrings = {
            id(node.body[0].value)
            for node in ast.walk(tree)
            if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef)) and node.body and isinstance(node.body[0], ast.Expr)
        }
        texts = {}  # an f-string as one text, its pieces left out
        for node in ast.walk(tree):
            if isinstance(node, ast.JoinedStr):
                texts[id(node)] = "{}".join(part.value if isinstance(part, ast.Constant) else "" for part in node.values)
                docstrings |= {id(part) for part in node.values}
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
                texts[id(node)] = node.value
        for text in texts.values():
            if re.search(r"(^|[\s(])--[a-z]", text) and "stlopt " not in text:
                found.append(f"{path.name}: {text!r}")
    return found


def test_robustness_with_parts_prints_each_part_whose_composition_is_the_total():
    from stl_lfd.stl import Semantics

    result = CliRunner().invoke(app, ["robustness", str(ROOT / "specs" / "phi1.stl"), str(ROOT / "examples" / "three_regions.csv"), "--json", "--parts"])
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert list(data["parts"]) == ["F L1", "G[12, 17] L2", "F L3", "F[8, 12] L4"]
    composed = Semantics("new", 1.0).kernels.conjunction(np.array(list(data["parts"].values())))
    assert float(composed) == pytest.approx(data["robustness"], rel=1e-12)
    plain = CliRunner().invoke(app, ["robustness", str(ROOT / "specs" / "phi1.stl"), str(ROOT / "examples" / "three_regions.csv")])
    assert "parts" not in plain.stdout and len(plain.stdout.splitlines()) == 1
