"""The documentation site: the command-line page covers every command and option that `--help`
lists, the result pages are what the recorded runs give, and the site builds without a warning."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
from itertools import takewhile
from pathlib import Path

import pytest
import typer.main

from stl_lfd.cli import app
from tests.conftest import ROOT

CLI_PAGE = ROOT / "docs" / "cli.md"
COMMANDS = typer.main.get_command(app).commands


def cli_sections() -> dict[str, str]:
    """Command name -> the text of its section (`## `stlopt NAME``) on the command-line page."""
    sections: dict[str, str] = {}
    for section in re.split(r"^## ", CLI_PAGE.read_text(), flags=re.M)[1:]:
        heading = section.splitlines()[0]
        match = re.fullmatch(r"`stlopt ([a-z-]+)`", heading.strip())
        if match:
            sections[match.group(1)] = section
    return sections


def listed_options(command) -> list[str]:
    """The option names (`-K`, `--states`, ...) that `stlopt COMMAND --help` lists, but --help
    (Typer's own click: its options are told by `param_type_name`)."""
    return [
        name for parameter in command.params if parameter.param_type_name == "option" and not getattr(parameter, "hidden", False) for name in parameter.opts
    ]


def test_every_command_has_a_section_on_the_cli_page():
    sections = cli_sections()
    assert sorted(sections) == sorted(COMMANDS), "commands of stlopt without a section (or sections without a command)"


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_the_cli_page_lists_every_option_of_the_command(name):
    section = cli_sections().get(name, "")
    missing = [option for option in listed_options(COMMANDS[name]) if not re.search(rf"(?<![\w-]){re.escape(option)}(?![\w-])", section)]
    assert not missing, f"docs/cli.md, section `stlopt {name}`, does not mention {', '.join(missing)}"


def test_the_options_are_what_help_prints():
    """The options checked above are the ones `--help` shows (the introspection is not blind)."""
    from typer.testing import CliRunner

    for name, command in COMMANDS.items():
        printed = CliRunner().invoke(app, [name, "--help"], env={"COLUMNS": "200"}).output
        assert all(option in printed for option in listed_options(command)), name
    assert {"-K", "--states", "-o", "--output", "--plot"} <= set(listed_options(COMMANDS["learn"]))
    assert "--help" not in listed_options(COMMANDS["learn"])


def argument_names(command) -> list[str]:
    """The positional arguments' names as `stlopt COMMAND --help` shows them (their metavars)."""
    return [parameter.metavar or parameter.name.upper() for parameter in command.params if parameter.param_type_name == "argument"]


def usage_arguments(line: str, name: str) -> list[str]:
    """The upper-case words after `stlopt NAME` in a usage line, up to its first option."""
    words = line.split(f"stlopt {name}", 1)[1].split()
    return list(takewhile(lambda word: re.fullmatch(r"[A-Z][A-Z_]*", word), words))


def readme_usages() -> dict[str, str]:
    """Command name -> its usage in the README's command table."""
    rows = re.findall(r"^\| `(stlopt ([a-z]+)[^`]*)`", (ROOT / "README.md").read_text(), flags=re.M)
    return {name: usage for usage, name in rows}


@pytest.mark.parametrize("name", sorted(COMMANDS))
def test_the_docs_name_the_arguments_as_help_does(name):
    names = argument_names(COMMANDS[name])
    section = cli_sections()[name]
    usage_block = section.split("```text", 1)[1].split("```", 1)[0]
    usages = [line for line in usage_block.splitlines() if line.startswith(f"stlopt {name}")]
    assert usages, f"docs/cli.md, section `stlopt {name}`: no usage line"
    for line in [*usages, readme_usages()[name]]:
        shown = usage_arguments(line, name)
        assert shown == names[: len(shown)], f"{line!r} names the arguments {shown}, --help {names}"
        required = [parameter.metavar for parameter in COMMANDS[name].params if parameter.param_type_name == "argument" and parameter.required]
        assert len(shown) >= len(required), f"{line!r} leaves out {required[len(shown) :]}"


def test_the_result_pages_are_generated_from_the_records():
    from benchmarks.results_pages import PAGES_DIR, pages

    generated = pages()
    assert "search.md" in generated and any(name.startswith("suite") for name in generated)
    on_disk = {path.name: path.read_text() for path in PAGES_DIR.glob("*.md")}
    stale = sorted(name for name in set(generated) | set(on_disk) if generated.get(name) != on_disk.get(name))
    assert not stale, f"docs/results/ differs from the records in {', '.join(stale)}: run python -m benchmarks.results_pages"


@pytest.mark.slow
def test_the_site_builds_without_warnings(tmp_path):
    mkdocs = Path(sys.executable).parent / "mkdocs"
    command = [str(mkdocs)] if mkdocs.exists() else [shutil.which("mkdocs") or "mkdocs"]
    result = subprocess.run([*command, "build", "--strict", "--site-dir", str(tmp_path / "site")], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr[-2000:]
    assert (tmp_path / "site" / "cli" / "index.html").exists() and (tmp_path / "site" / "reference" / "stl" / "index.html").exists()


def test_the_scene_file_example_loads_with_every_key_it_explains(tmp_path):
    from stl_lfd.sim import load_scene

    page = (ROOT / "docs" / "execution.md").read_text()
    example = page.split("### A scene file", 1)[1].split("```yaml\n", 1)[1].split("```", 1)[0]
    (tmp_path / "shelf.yaml").write_text(example)
    scene = load_scene(str(tmp_path / "shelf.yaml"))
    can = next(item for item in scene.objects if item.name == "can")
    assert can.size == (0.02, 0.08) and can.mass == 0.1 and {frame.name for frame in scene.frames} == {"can", "shelf"}
