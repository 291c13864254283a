"""The package's layout, read from its import statements (ast; nothing is imported or run).

The rules of docs/contracts.md ("Layout"): the package root holds only ``__init__`` and
``__main__``; ``core/`` is the ground floor (it imports nothing of the package outside
``core/``); no domain module imports the command line (``commands/``); and no module imports
itself back through a chain of imports (a cycle), deferred (function-level) imports included.
"""

from __future__ import annotations

import ast
from functools import cache
from pathlib import Path

import pytest

PACKAGE = Path(__file__).resolve().parents[2] / "pipeline" / "spindlebench"


def module_name(path: Path) -> str:
    parts = list(path.relative_to(PACKAGE.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


MODULES: dict[str, Path] = {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _statements(body: list[ast.stmt], deferred: bool):
    """The import statements among ``body``: those run at import time, and with ``deferred``
    also those inside functions; never an ``if TYPE_CHECKING:`` block (not run at all)."""
    for node in body:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
        elif isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            yield from _statements(node.orelse, deferred)
        elif isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
            if deferred:
                yield from _statements(node.body, deferred)
        else:
            for field in ("body", "orelse", "finalbody", "handlers"):
                inner = getattr(node, field, None)
                if isinstance(inner, list):
                    yield from _statements([n for n in inner if isinstance(n, ast.AST)], deferred)


@cache
def imports_of(module: str, deferred: bool = True) -> frozenset[str]:
    """The package modules ``module`` imports (at import time, and with ``deferred`` also
    inside functions). ``from pkg import x`` counts as importing ``pkg.x`` when that is a
    module, else ``pkg``."""
    path = MODULES[module]
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    found: set[str] = set()
    for node in _statements(tree.body, deferred):
        if isinstance(node, ast.Import):
            found.update(a.name for a in node.names if a.name.split(".")[0] == "spindlebench")
        elif node.level:
            raise AssertionError(f"{path}:{node.lineno}: relative import (use absolute ones)")
        elif node.module and node.module.split(".")[0] == "spindlebench":
            for alias in node.names:
                sub = f"{node.module}.{alias.name}"
                found.add(sub if sub in MODULES else node.module)
    unknown = sorted(name for name in found if name not in MODULES)
    assert not unknown, f"{path}: imports modules that do not exist: {unknown}"
    return frozenset(found - {module})


def subpackage(module: str) -> str:
    """The unit of layering: ``spindlebench.X`` (``spindlebench.studies.X`` under studies/)."""
    parts = module.split(".")
    depth = 3 if parts[1:2] == ["studies"] and len(parts) > 3 else 2
    return ".".join(parts[:depth])


def test_the_package_root_holds_only_init_and_main():
    loose = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert loose == ["__init__.py", "__main__.py"]


def test_every_folder_of_the_package_is_a_package():
    for folder in PACKAGE.rglob("*"):
        if folder.is_dir() and folder.name != "__pycache__" and any(folder.glob("*.py")):
            assert (folder / "__init__.py").is_file(), f"{folder}: no __init__.py"


@pytest.mark.parametrize("module", sorted(m for m in MODULES if m.startswith("spindlebench.core")))
def test_core_imports_nothing_above_it(module):
    above = sorted(name for name in imports_of(module)
                   if name != "spindlebench" and not name.startswith("spindlebench.core"))
    assert not above, f"{module} (ground floor) imports {above}"


def test_no_domain_module_imports_the_command_line():
    """Only the command line itself and ``python -m spindlebench`` (``__main__``) do."""
    domain = [m for m in MODULES
              if not m.startswith("spindlebench.commands") and m != "spindlebench.__main__"]
    offenders = {module: sorted(n for n in imports_of(module)
                                if n.startswith("spindlebench.commands")) for module in domain}
    assert not {m: found for m, found in offenders.items() if found}


def test_the_package_root_is_imported_only_for_its_version():
    """``spindlebench/__init__`` is the public face; a module that needs anything but
    ``__version__`` from it imports the module where the thing lives."""
    for module, path in MODULES.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module == "spindlebench":
                names = [a.name for a in node.names if a.name != "__version__"
                         and f"spindlebench.{a.name}" not in MODULES]
                assert not names, f"{module}:{node.lineno}: imports {names} from the root"


def find_cycle(graph: dict[str, frozenset[str]]) -> list[str] | None:
    """One cycle of ``graph`` (node -> the nodes it imports), by depth-first search, or None."""
    state: dict[str, int] = {}  # 1 while on the current path, 2 when finished
    path: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        path.append(node)
        for target in sorted(graph.get(node, ())):
            if state.get(target) == 1:
                return [*path[path.index(target):], target]
            if target not in state and (cycle := visit(target)):
                return cycle
        path.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (cycle := visit(node)):
            return cycle
    return None


def import_time_graph() -> dict[str, frozenset[str]]:
    return {module: imports_of(module, deferred=False) for module in MODULES}


def subpackage_graph() -> dict[str, frozenset[str]]:
    """Which subpackage imports which, deferred imports included."""
    graph: dict[str, set[str]] = {}
    for module in MODULES:
        home = subpackage(module)
        edges = graph.setdefault(home, set())
        # the root is the public face above every floor; below it only ``__version__`` is
        # taken from it (``test_the_package_root_is_imported_only_for_its_version``)
        edges.update(subpackage(t) for t in imports_of(module)
                     if subpackage(t) not in (home, "spindlebench"))
    return {node: frozenset(edges) for node, edges in graph.items()}


def test_no_import_cycle_at_import_time():
    cycle = find_cycle(import_time_graph())
    assert cycle is None, "import cycle: " + " -> ".join(cycle or [])


def test_no_cycle_between_subpackages():
    """Layers: a subpackage never imports one that imports it back, not even in a function.
    (Inside one subpackage a deferred import back is allowed: ``selection.select`` hands
    pair candidates to ``selection.pairs``, which builds on it; ``calibration.problem``
    imports its optional IPOPT solver only when asked for.)"""
    cycle = find_cycle(subpackage_graph())
    assert cycle is None, "subpackages in a cycle: " + " -> ".join(cycle or [])


def test_the_cycle_finder_finds_a_cycle():
    """The checks above could fail: an edge core -> commands closes a cycle (commands
    imports core)."""
    graph = dict(subpackage_graph())
    graph["spindlebench.core"] = graph["spindlebench.core"] | {"spindlebench.commands"}
    cycle = find_cycle(graph)
    assert cycle is not None and "spindlebench.core" in cycle
