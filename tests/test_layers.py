"""The import graph follows the layers of the design: `cli -> (dashboard, progress) -> report -> optim -> skill ->
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
LEAVES = {"allocator", "choices", "dag", "errors", "files", "key_positions", "lazy", "limits", "poses", "rotations", "signals", "spelling", "yamlfile"}
# Higher ranks may import lower ones (and themselves); equal ranks only themselves.
RANKS = {"leaf": 0, "stl": 1, "hsmm": 1, "sim": 1, "skill": 2, "optim": 3, "report": 4, "progress": 5, "dashboard": 5, "cli": 6, "__init__": 7}


def layer(module: str) -> str:
    """`stl_lfd.optim.runs.prepare` -> `optim`; leaf utilities -> `leaf`."""
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


def import_graph(typing: bool = False) -> dict[str, set[str]]:
    """Module -> the stl_lfd modules it imports (anywhere but, unless `typing`, under `if
    TYPE_CHECKING`), with `from package import module` counted as an import of the module, not
    of the package."""
    modules = {module_name(path): path for path in PACKAGE.rglob("*.py")}
    graph = {}
    for name, path in modules.items():
        tree = ast.parse(path.read_text())
        typing_only = {
            id(node) for block in ast.walk(tree) if isinstance(block, ast.If) and getattr(block.test, "id", "") == "TYPE_CHECKING" for node in ast.walk(block)
        }
        targets = set()
        for node in ast.walk(tree):
            if id(node) in typing_only and not typing:
                continue
            if isinstance(node, ast.Import):
                targets |= {alias.name for alias in node.names if alias.name in modules}
            elif isinstance(node, ast.ImportFrom) and node.module in modules:
                submodules = {f"{node.module}.{alias.name}" for alias in node.names} & set(modules)
                targets |= submodules or {node.module}
                if len(submodules) < len(node.names):
                    targets.add(node.module)
        graph[name] = targets - {name}
    return graph


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The import cycles of `graph` (its strongly connected components of more than one module)."""
    order, low, stack, found, counter = {}, {}, [], [], iter(range(len(graph) * 2))

    def visit(module: str) -> None:
        order[module] = low[module] = next(counter)
        stack.append(module)
        for target in graph[module]:
            if target not in order:
                visit(target)
                low[module] = min(low[module], low[target])
            elif target in stack:
                low[module] = min(low[module], order[target])
        if low[module] == order[module]:
            component = []
            while not component or component[-1] != module:
                component.append(stack.pop())
            if len(component) > 1:
                found.append(sorted(component))

    for module in sorted(graph):
        if module not in order:
            visit(module)
    return found


def test_no_import_cycles():
    assert cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert cycles(import_graph()) == []
    assert cycles(import_graph(typing=True)) == []  # not even through imports made for type hints


def test_the_optimiser_is_small_modules():
    lengths = {path.relative_to(ROOT).as_posix(): len(path.read_text().splitlines()) for path in (PACKAGE / "optim").rglob("*.py")}
    assert {path: length for path, length in lengths.items() if length > 300} == {}
