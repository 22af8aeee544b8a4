"""docs/architecture.md, the map for newcomers, names every sub-package of stl_lfd, every
command, every registry it sends a contributor to, and only files that exist."""

import re

from tests.conftest import ROOT

PAGE = (ROOT / "docs" / "architecture.md").read_text()


def test_the_map_names_every_sub_package_and_command():
    packages = sorted(path.parent.relative_to(ROOT).as_posix() for path in (ROOT / "stl_lfd").glob("*/__init__.py"))
    assert [package for package in packages if f"`{package}`" not in PAGE] == []
    from stl_lfd.cli import app

    commands = [command.name or command.callback.__name__ for command in app.registered_commands]
    assert len(commands) >= 10 and [command for command in commands if f"`stlopt {command}`" not in PAGE] == []


def test_every_file_and_registry_it_names_exists():
    named = set(re.findall(r"`((?:stl|hsmm|sim|skill|optim|report|dashboard|cli)/[\w/]+\.(?:py|lark))", PAGE))
    assert len(named) > 25
    assert sorted(path for path in named if not (ROOT / "stl_lfd" / path).is_file()) == []
    sources = {path: (ROOT / "stl_lfd" / path).read_text() for path in named}
    for registry, path in (
        ("REGISTRY", "optim/method_registry.py"),
        ("REGISTRY", "sim/registry.py"),
        ("FIGURES", "report/figures/__init__.py"),
        ("SETTINGS", "optim/method_registry.py"),
    ):
        assert re.search(rf"^{registry}\b", sources[path], re.M), (registry, path)
