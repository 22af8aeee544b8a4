"""The benchmarks use stlopt as its users do: through the public API, the names each package
exports (`__all__` of `stl_lfd` and of its packages), never a module inside a package. So a
refactoring inside a package cannot break them, and what they need is documented API."""

import ast
import importlib

from tests.conftest import ROOT

PUBLIC = (
    "stl_lfd",
    "stl_lfd.stl",
    "stl_lfd.hsmm",
    "stl_lfd.sim",
    "stl_lfd.skill",
    "stl_lfd.optim",
    "stl_lfd.optim.methods",
    "stl_lfd.report",
    "stl_lfd.dashboard",
)


def benchmark_imports() -> list[tuple[str, str, str]]:
    """(file, module, name) of every `from stl_lfd... import name` and `import stl_lfd...` in benchmarks/."""
    found = []
    for path in sorted((ROOT / "benchmarks").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("stl_lfd"):
                found += [(path.name, node.module, alias.name) for alias in node.names]
            elif isinstance(node, ast.Import):
                found += [(path.name, alias.name, "") for alias in node.names if alias.name.startswith("stl_lfd")]
    return found


def test_benchmarks_import_only_what_the_packages_export():
    imports = benchmark_imports()
    assert len(imports) > 40
    outside = [f"{file}: {module}" for file, module, _ in imports if module not in PUBLIC]
    assert outside == []
    unexported = [f"{file}: {module}.{name}" for file, module, name in imports if name and name not in importlib.import_module(module).__all__]
    assert unexported == []
