"""The import graph follows the layers of the design: `cli -> report -> optim -> skill ->
(stl, hsmm, sim)`, leaf utilities below everything, `stl`, `hsmm` and `sim` never importing
each other, nothing importing the CLI, and `import stl_lfd` loading neither torch nor pybullet.

Every import counts, including those inside functions.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import ROOT

PACKAGE = ROOT / "stl_lfd"
LEAVES = {"choices", "dag", "errors", "files", "lazy", "limits", "poses", "signals", "yamlfile"}
# Higher ranks may import lower ones (and themselves); equal ranks only themselves.
RANKS = {"leaf": 0, "stl": 1, "hsmm": 1, "sim": 1, "skill": 2, "optim": 3, "report": 4, "progress": 5, "cli": 6, "__init__": 7}


def layer(module: str) -> str:
    """`stl_lfd.optim.run` -> `optim`; leaf utilities -> `leaf`."""
    parts = module.split(".")
    if len(parts) == 1:
        return "__init__"
    return "leaf" if parts[1] in LEAVES else parts[1]


def imports_of(path: Path) -> set[str]:
    """The stl_lfd modules a file imports, anywhere in it."""
    tree = ast.parse(path.read_text())
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {alias.name for alias in node.names if alias.name.startswith("stl_lfd")}
        elif isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("stl_lfd"):
            found.add(node.module)
    return found


def module_name(path: Path) -> str:
    relative = path.relative_to(ROOT).with_suffix("")
    parts = relative.parts[:-1] if relative.name == "__init__" else relative.parts
    return ".".join(parts)


def wrong_arrows() -> list[str]:
    problems = []
    for path in sorted(PACKAGE.rglob("*.py")):
        source = module_name(path)
        for target in imports_of(path):
            if not allowed(layer(source), layer(target)):
                problems.append(f"{source} -> {target}")
    return problems


def allowed(source: str, target: str) -> bool:
    if source == target:
        return True
    if target == "cli" or target not in RANKS or source not in RANKS:
        return False
    return RANKS[target] < RANKS[source]


def test_the_rule_itself():
    assert allowed("optim", "skill") and allowed("skill", "hsmm") and allowed("report", "leaf")
    assert not allowed("skill", "optim") and not allowed("stl", "hsmm") and not allowed("sim", "stl")
    assert not allowed("report", "cli") and not allowed("leaf", "stl")


def test_imports_follow_the_layers():
    assert wrong_arrows() == []


@pytest.mark.parametrize("module", ["stl_lfd", "stl_lfd.stl", "stl_lfd.hsmm", "stl_lfd.cli"])
def test_light_imports_load_no_heavy_library(module):
    code = f"import sys, {module}; print(','.join(name for name in ('torch', 'botorch', 'pybullet', 'matplotlib', 'scipy.ndimage') if name in sys.modules))"
    loaded = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.strip()
    assert loaded == ""
