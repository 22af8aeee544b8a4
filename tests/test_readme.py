"""The README's console examples: every `$` command runs, in order, in a scratch folder that
holds the repository's specs, examples, demos and configs, and prints what the README shows.

How an example's output is compared with what the command printed (stdout and stderr):
- a line `...` stands for any number of lines; otherwise every stdout line must be shown;
- `# (stderr)` at the end of a line is a comment;
- whitespace runs count as one space;
- numbers must be equal as written, except a number written with a trailing `...` (a prefix
  of the printed one), a number written with a trailing `~` (one that the Gaussian process's
  proposals decide, which differs between processors of different kinds: any number of the
  same sign), and durations (a number followed by `s` or `x real time`), which vary from
  machine to machine.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.conftest import ROOT

NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:e[-+]?\d+)?(?:\.\.\.|~)?")
DURATION_AFTER = re.compile(r"^ ?(s\b|x real time)")
STANDALONE_COMMANDS = ("stlopt optimize", "stlopt replay", "stlopt sweep")  # write nothing a later example reads
# Examples that learn, execute or start Python take seconds each: marked slow (left out by `-m "not slow"`).
SLOW_COMMANDS = STANDALONE_COMMANDS + ("stlopt learn", "stlopt retrieve", "stlopt rollout", "stlopt ask", "stlopt tell", "python ")


@dataclass
class Example:
    command: str
    expected: list[str]
    line: int


def console_examples(text: str) -> list[Example]:
    """The `$` commands of the README's console blocks with the lines shown after each."""
    examples: list[Example] = []
    inside = False
    for number, line in enumerate(text.splitlines(), start=1):
        if line.startswith("```"):
            inside = line.strip() == "```console"
            continue
        if not inside:
            continue
        if line.startswith("$ "):
            examples.append(Example(line[2:], [], number))
        elif examples:
            examples[-1].expected.append(line.split("# (stderr)")[0].rstrip())
    return examples


def _tokens(line: str) -> list[str]:
    return [token for token in re.split(f"({NUMBER.pattern})", " ".join(line.split())) if token]


def line_matches(expected: str, printed: str) -> bool:
    """Whether a printed line is the one the README shows (see the module docstring)."""
    want, got = _tokens(expected), _tokens(printed)
    if len(want) != len(got):
        return False
    for index, (token, actual) in enumerate(zip(want, got)):
        if not NUMBER.fullmatch(token):
            if token != actual:
                return False
            continue
        following = want[index + 1] if index + 1 < len(want) else ""
        if DURATION_AFTER.match(following):
            continue
        if token.endswith("~"):
            if token[0] in "+-" and actual[0] != token[0]:
                return False
        elif token.endswith("..."):
            if not actual.startswith(token[:-3]):
                return False
        elif token != actual:
            return False
    return True


def output_matches(expected: list[str], stdout: str, stderr: str) -> str:
    """'' when the output is what the README shows, else what is missing or extra."""
    printed = [line for line in stdout.splitlines() + stderr.splitlines() if line.strip()]
    shown = [line for line in expected if line.strip()]
    unmatched = list(printed)
    for line in shown:
        if line.strip() == "...":
            continue
        found = next((candidate for candidate in unmatched if line_matches(line, candidate)), None)
        if found is None:
            return f"the README shows {line!r}, which was not printed"
        unmatched.remove(found)
    extra = [line for line in unmatched if line in stdout.splitlines()]
    if extra and not any(line.strip() == "..." for line in shown):
        return f"printed {extra[0]!r}, which the README does not show"
    return ""


EXAMPLES = console_examples((ROOT / "README.md").read_text())


def test_the_readme_has_console_examples_and_the_matcher_works():
    assert len(EXAMPLES) >= 8
    assert line_matches("-0.03572971192...", "-0.035729711921")
    assert not line_matches("-0.0357...", "-0.0358")
    assert line_matches("best: trial 11~, robustness +0.02205~", "best: trial 31, robustness +0.02254")
    assert not line_matches("robustness +0.02205~", "robustness -0.00254")
    assert not line_matches("robustness +0.02205~ (satisfied)", "robustness +0.02205 (violated)")
    assert line_matches("rollout: 22.00 s simulated in 0.56 s (39x real time)", "rollout: 22.00 s simulated in 1.52 s (15x real time)")
    assert not line_matches("tracking error RMS 0.07 mm", "tracking error RMS 0.06 mm")
    assert output_matches(["a 1", "..."], "a 1\nb 2\n", "") == ""
    assert "does not show" in output_matches(["a 1"], "a 1\nb 2\n", "")


@pytest.fixture(scope="module")
def scratch(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("readme")
    for name in ("specs", "examples", "demos", "configs"):
        (folder / name).symlink_to(ROOT / name)
    (folder / "sweeps").mkdir()  # sweep files only: a sweep's output must not land in the repository
    for path in (ROOT / "sweeps").glob("*.yaml"):
        (folder / "sweeps" / path.name).symlink_to(path)
    return folder


def _is_slow(example: Example) -> bool:
    return any(command in example.command for command in SLOW_COMMANDS)


def _marks(example: Example) -> list[pytest.MarkDecorator]:
    """Slow examples are marked `slow`; the standalone ones (a whole optimisation, a filmed
    replay, a sweep) are the longest tests of all: `heavy` too. All run in one test process
    (`xdist_group`), so that the examples they follow run once."""
    marks = [pytest.mark.xdist_group("readme")]
    if example.command.startswith(STANDALONE_COMMANDS):
        return marks + [pytest.mark.slow, pytest.mark.heavy]
    return marks + ([pytest.mark.slow] if _is_slow(example) else [])


def _needs(index: int, earlier: int) -> bool:
    """Whether example `index` runs after example `earlier`: examples use the files earlier ones
    wrote, except those of the standalone ones (a full optimisation, a filmed replay and a
    sweep); a fast example needs only the fast ones before it."""
    before = EXAMPLES[earlier]
    return not before.command.startswith(STANDALONE_COMMANDS) and (_is_slow(EXAMPLES[index]) or not _is_slow(before))


_done: dict[int, subprocess.CompletedProcess] = {}


def _run_up_to(index: int, folder: Path) -> subprocess.CompletedProcess:
    """Run example `index` after the earlier ones it needs (`_needs`)."""
    for earlier in range(index + 1):
        if earlier not in _done and (earlier == index or _needs(index, earlier)):
            environment = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}", COLUMNS="200")
            _done[earlier] = subprocess.run(
                ["bash", "-o", "pipefail", "-c", EXAMPLES[earlier].command], cwd=folder, env=environment, capture_output=True, text=True, timeout=900
            )
    return _done[index]


@pytest.mark.parametrize(
    "index",
    [pytest.param(index, marks=_marks(example), id=f"line{example.line}") for index, example in enumerate(EXAMPLES)],
)
def test_readme_console_example(index, scratch):
    example = EXAMPLES[index]
    result = _run_up_to(index, scratch)
    expects_error = any(line.startswith("error:") for line in example.expected)
    assert (result.returncode != 0) == expects_error, f"README line {example.line}: `{example.command}` exited {result.returncode}: {result.stderr[-500:]}"
    problem = output_matches(example.expected, result.stdout, result.stderr)
    assert not problem, f"README line {example.line}: `{example.command}`: {problem}"
