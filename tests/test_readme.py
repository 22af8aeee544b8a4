"""The console examples of the README and of every documentation page (`docs/*.md`): each
page's `$` commands run, in order, in a scratch folder of the page's own that holds the
repository's specs, examples, demos and configs, and print what the page shows. A code block
whose info string names a file (```` ```yaml title="mine.yaml" ````) is that file of the
page's scratch folder, written before its commands run.

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
STANDALONE_COMMANDS = ("stlopt optimize", "stlopt replay", "stlopt sweep")  # write nothing a later example reads, unless it names their --out
# Examples that learn, execute or start Python take seconds each: marked slow (left out by `-m "not slow"`).
SLOW_COMMANDS = STANDALONE_COMMANDS + ("stlopt learn", "stlopt retrieve", "stlopt rollout", "stlopt ask", "stlopt tell", "python ")
FILE_BLOCK = re.compile(r'^```\w*\s+title="([^"/]+)"\s*$')
PAGES = ["README.md"] + [path.relative_to(ROOT).as_posix() for path in sorted((ROOT / "docs").glob("*.md"))]


@dataclass
class Example:
    command: str
    expected: list[str]
    line: int


def console_examples(text: str) -> list[Example]:
    """The `$` commands of a page's console blocks with the lines shown after each."""
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


def file_blocks(text: str) -> dict[str, str]:
    """The files a page shows in code blocks with a `title="NAME"` (a plain file name)."""
    files: dict[str, str] = {}
    name, lines = None, []
    for line in text.splitlines():
        if name is None:
            match = FILE_BLOCK.match(line)
            if match:
                name, lines = match.group(1), []
        elif line.startswith("```"):
            files[name] = "\n".join(lines) + "\n"
            name = None
        else:
            lines.append(line)
    return files


def _tokens(line: str) -> list[str]:
    return [token for token in re.split(f"({NUMBER.pattern})", " ".join(line.split())) if token]


def line_matches(expected: str, printed: str) -> bool:
    """Whether a printed line is the one the page shows (see the module docstring)."""
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
    """'' when the output is what the page shows, else what is missing or extra."""
    printed = [line for line in stdout.splitlines() + stderr.splitlines() if line.strip()]
    shown = [line for line in expected if line.strip()]
    unmatched = list(printed)
    for line in shown:
        if line.strip() == "...":
            continue
        found = next((candidate for candidate in unmatched if line_matches(line, candidate)), None)
        if found is None:
            return f"the page shows {line!r}, which was not printed"
        unmatched.remove(found)
    extra = [line for line in unmatched if line in stdout.splitlines()]
    if extra and not any(line.strip() == "..." for line in shown):
        return f"printed {extra[0]!r}, which the page does not show"
    return ""


TEXTS = {page: (ROOT / page).read_text() for page in PAGES}
EXAMPLES = {page: console_examples(text) for page, text in TEXTS.items()}
FILES = {page: file_blocks(text) for page, text in TEXTS.items()}


def test_the_pages_have_console_examples_and_the_matcher_works():
    assert len(EXAMPLES["README.md"]) >= 4
    assert sum(len(examples) for examples in EXAMPLES.values()) >= 16
    assert FILES["README.md"], "the README's first own task shows its files"
    assert line_matches("-0.03572971192...", "-0.035729711921")
    assert not line_matches("-0.0357...", "-0.0358")
    assert line_matches("best: trial 11~, robustness +0.02205~", "best: trial 31, robustness +0.02254")
    assert not line_matches("robustness +0.02205~", "robustness -0.00254")
    assert not line_matches("robustness +0.02205~ (satisfied)", "robustness +0.02205 (violated)")
    assert line_matches("rollout: 22.00 s simulated in 0.56 s (39x real time)", "rollout: 22.00 s simulated in 1.52 s (15x real time)")
    assert not line_matches("tracking error RMS 0.07 mm", "tracking error RMS 0.06 mm")
    assert output_matches(["a 1", "..."], "a 1\nb 2\n", "") == ""
    assert "does not show" in output_matches(["a 1"], "a 1\nb 2\n", "")
    assert file_blocks('x\n```yaml title="a.yaml"\nk: 1\n```\n```yaml title="dir/b.yaml"\nk: 2\n```\n') == {"a.yaml": "k: 1\n"}


_scratch: dict[str, Path] = {}


@pytest.fixture(scope="session")
def scratch(tmp_path_factory):
    """A page's scratch folder (made on first use): the repository's inputs and the page's files."""

    def folder_of(page: str) -> Path:
        if page not in _scratch:
            folder = tmp_path_factory.mktemp(Path(page).stem)
            for name in ("specs", "examples", "demos"):
                (folder / name).symlink_to(ROOT / name)
            # folders of links: what an example writes there (a sweep's output, an edited task file)
            # must not land in the repository
            for name in ("configs", "sweeps"):
                (folder / name).mkdir()
                for path in (ROOT / name).iterdir():
                    (folder / name / path.name).symlink_to(path)
            for name, text in FILES[page].items():
                (folder / name).write_text(text)
            _scratch[page] = folder
        return _scratch[page]

    return folder_of


def _is_slow(example: Example) -> bool:
    return any(command in example.command for command in SLOW_COMMANDS)


def _is_standalone(example: Example) -> bool:
    return example.command.startswith(STANDALONE_COMMANDS)


def _reads_output_of(example: Example, earlier: Example) -> bool:
    """Whether `example` reads the run directory that the standalone `earlier` writes (`--out`)."""
    out = re.search(r"--out\s+(\S+)", earlier.command)
    return out is not None and re.search(rf"(?<![\w/.-]){re.escape(out.group(1))}(?![\w.-])", example.command) is not None


def _needs(examples: list[Example], index: int, earlier: int) -> bool:
    """Whether example `index` runs after example `earlier`: examples use the files earlier ones
    wrote, except those of the standalone ones (a full optimisation, a filmed replay and a
    sweep) unless they read its `--out`; a fast example needs only the fast ones before it."""
    before, example = examples[earlier], examples[index]
    if _is_standalone(before):
        return _reads_output_of(example, before)
    return _is_slow(example) or not _is_slow(before)


def _marks(page: str, index: int) -> list[pytest.MarkDecorator]:
    """Slow examples are marked `slow`; the standalone ones (a whole optimisation, a filmed
    replay, a sweep), and those that read their output, are the longest tests of all: `heavy`
    too. A page's examples run in one test process (`xdist_group`), so that the examples they
    follow run once."""
    examples = EXAMPLES[page]
    marks = [pytest.mark.xdist_group(f"examples:{page}")]
    example = examples[index]
    if _is_standalone(example) or any(_is_standalone(examples[earlier]) and _needs(examples, index, earlier) for earlier in range(index)):
        return marks + [pytest.mark.slow, pytest.mark.heavy]
    return marks + ([pytest.mark.slow] if _is_slow(example) else [])


_done: dict[tuple[str, int], subprocess.CompletedProcess] = {}


def _run_up_to(page: str, index: int, folder: Path) -> subprocess.CompletedProcess:
    """Run example `index` of a page after the earlier ones it needs (`_needs`)."""
    examples = EXAMPLES[page]
    for earlier in range(index + 1):
        if (page, earlier) not in _done and (earlier == index or _needs(examples, index, earlier)):
            environment = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}", COLUMNS="200")
            _done[(page, earlier)] = subprocess.run(
                ["bash", "-o", "pipefail", "-c", examples[earlier].command], cwd=folder, env=environment, capture_output=True, text=True, timeout=900
            )
    return _done[(page, index)]


@pytest.mark.parametrize(
    "page, index",
    [pytest.param(page, index, marks=_marks(page, index), id=f"{page}:{example.line}") for page in PAGES for index, example in enumerate(EXAMPLES[page])],
)
def test_console_example(page, index, scratch):
    example = EXAMPLES[page][index]
    result = _run_up_to(page, index, scratch(page))
    expects_error = any(line.startswith("error:") for line in example.expected)
    where = f"{page} line {example.line}: `{example.command}`"
    assert (result.returncode != 0) == expects_error, f"{where} exited {result.returncode}: {result.stderr[-500:]}"
    problem = output_matches(example.expected, result.stdout, result.stderr)
    assert not problem, f"{where}: {problem}"


def recipe_lines(makefile: str, target: str) -> list[str]:
    """The recipe lines (tab-indented, continuations joined) of `target` in a Makefile's text."""
    body = makefile.split(f"\n{target}:", 1)[1].split("\n\n", 1)[0]
    joined = body.replace("\\\n", " ")
    return [line[1:] for line in joined.splitlines()[1:] if line.startswith("\t")]


@pytest.mark.parametrize("target", ["$(STAMP)", "run"])
def test_make_run_echoes_no_recipe_line(target):
    """`make run` speaks in sentences: every line of its recipes (and the install's) is silent (@)."""
    lines = recipe_lines((ROOT / "Makefile").read_text(), target)
    assert lines, f"no recipe for {target}"
    assert all(line.startswith("@") for line in lines), [line for line in lines if not line.startswith("@")]
    echoes = [line for line in lines if line.startswith("@echo")]
    assert len(echoes) == {"$(STAMP)": 2, "run": 1}[target]  # before and after the install; where to watch the result
