"""The documentation site: the command-line page covers every command and option that `--help`
lists, the result pages are what the recorded runs give, and the site builds without a warning."""

from __future__ import annotations

import re
import shutil
import subprocess
import sys
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
