"""The package's shape: no import cycles, and a core that loads without the heavy back ends.

Why: the node API and the mission run in processes that need neither the simulator (pybullet),
the log format (mcap) nor the viewer (rerun); a core module that pulls one of them in makes
every process pay its import time and its native libraries. And an import cycle works only
by accident of import order.

Imports are read with :mod:`ast`, not by importing, so the graph covers every module.
"""

from __future__ import annotations

import ast
import graphlib
import subprocess
import sys
from pathlib import Path

import pytest

PACKAGE = "usar_replay"
ROOT = Path(__file__).resolve().parents[1] / PACKAGE

# Modules every process may import: they must not load a heavy back end. Add new core
# modules (the node API) here.
CORE_MODULES = (
    "msgs",
    "contract",
    "settings",
    "rotations",
    "errors",
    "tf_tree",
    "detect",
    "nav",
    "scenario",
    "variants",
    # the node API: what a mission process loads (it must stay light and never reach the log)
    "cdr",
    "cdrdecode",
    "node",
    "executor",
    "tf2",
    "navigation",
    "worker",
    "sandbox",
)
HEAVY = ("pybullet", "mcap", "rerun")


def _modules() -> dict[str, Path]:
    return {p.stem: p for p in sorted(ROOT.glob("*.py")) if p.stem != "__init__"}


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING"
    )


def _targets(node: ast.Import | ast.ImportFrom, modules: dict[str, Path]) -> set[str]:
    """The package modules one import statement loads."""
    out: set[str] = set()
    if isinstance(node, ast.Import):
        for alias in node.names:
            parts = alias.name.split(".")
            if parts[0] == PACKAGE and len(parts) > 1 and parts[1] in modules:
                out.add(parts[1])
        return out
    if node.level:  # relative: from . import x / from .x import y
        base = [PACKAGE] + ([node.module] if node.module else [])
    else:
        base = (node.module or "").split(".")
    if base[0] != PACKAGE:
        return out
    if len(base) > 1:
        if base[1] in modules:
            out.add(base[1])
    else:
        out.update(a.name for a in node.names if a.name in modules)
    return out


def import_graph() -> tuple[dict[str, set[str]], dict[str, set[str]]]:
    """(module-level edges, deferred edges): module-level imports run when the module is
    imported (class bodies and try blocks included); deferred ones are inside functions or
    under ``if TYPE_CHECKING:`` (never run)."""
    modules = _modules()
    top: dict[str, set[str]] = {m: set() for m in modules}
    deferred: dict[str, set[str]] = {m: set() for m in modules}

    def visit(node: ast.AST, name: str, is_deferred: bool) -> None:
        for child in ast.iter_child_nodes(node):
            d = is_deferred or isinstance(
                child, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda
            )
            if isinstance(child, ast.If) and _is_type_checking(child):
                for sub in child.body:
                    visit(ast.Module(body=[sub], type_ignores=[]), name, True)
                for sub in child.orelse:
                    visit(ast.Module(body=[sub], type_ignores=[]), name, d)
                continue
            if isinstance(child, ast.Import | ast.ImportFrom):
                (deferred if d else top)[name].update(_targets(child, modules) - {name})
            visit(child, name, d)

    for name, path in modules.items():
        visit(ast.parse(path.read_text(encoding="utf-8"), str(path)), name, False)
    return top, deferred


def _cycle(graph: dict[str, set[str]]) -> list[str]:
    try:
        graphlib.TopologicalSorter(graph).prepare()
    except graphlib.CycleError as e:
        return list(e.args[1])
    return []


def test_the_graph_reader_sees_imports() -> None:
    """A guard against a reader that finds nothing (and so no cycles)."""
    top, deferred = import_graph()
    assert "msgs" in top["tf_tree"]
    assert "rotations" in top["nav"]
    assert sum(len(v) for v in top.values()) > 20
    assert any(deferred.values())  # cli.py imports its commands lazily


def test_no_cycles_among_module_level_imports() -> None:
    top, _ = import_graph()
    assert _cycle(top) == [], f"import cycle at module level: {' -> '.join(_cycle(top))}"


def test_no_cycles_counting_deferred_imports_too() -> None:
    """Also the imports inside functions and under TYPE_CHECKING: a cycle there is a design
    smell (two modules that each need the other), even when import order hides it."""
    top, deferred = import_graph()
    both = {m: top[m] | deferred[m] for m in top}
    assert _cycle(both) == [], f"import cycle (with deferred imports): {' -> '.join(_cycle(both))}"


@pytest.mark.parametrize("module", CORE_MODULES)
def test_core_module_loads_no_heavy_back_end(module: str) -> None:
    """Imported alone in a fresh interpreter, a core module leaves none of pybullet, mcap,
    rerun in ``sys.modules``."""
    assert module in _modules(), f"{module} is listed as core but does not exist"
    code = (
        "import sys, importlib\n"
        f"importlib.import_module('{PACKAGE}.{module}')\n"
        f"heavy = {HEAVY!r}\n"
        "print(' '.join(sorted({k.split('.')[0] for k in sys.modules} & set(heavy))))\n"
    )
    out = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=120
    )
    assert out.stdout.strip() == "", f"{PACKAGE}.{module} imports {out.stdout.strip()}"


def test_the_package_ships_py_typed() -> None:
    """PEP 561: the marker file exists and the build lists it as package data."""
    import tomllib

    assert (ROOT / "py.typed").is_file()
    project = tomllib.loads((ROOT.parent / "pyproject.toml").read_text(encoding="utf-8"))
    assert "py.typed" in project["tool"]["setuptools"]["package-data"][PACKAGE]
