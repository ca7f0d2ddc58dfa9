"""The package's shape: folders are layers, each imports only the layers below it, no cycles,
and the layers a mission process loads never pull in a heavy back end.

Why: the tree is the architecture a newcomer reads (``usar_replay/<layer>/<module>.py``); these
rules keep it true. The node API and the mission run in processes that need neither the
simulator (pybullet), the log format (mcap) nor the viewer (rerun); a module of those layers
that pulls one in makes every mission process pay for it. An import cycle works only by
accident of import order.

Imports are read with :mod:`ast`, not by importing, so the graph covers every module, and
:func:`violations` takes any tree, so a deliberately misplaced module can be checked in a copy.
A string that names one of usar's modules (``"usar_replay.api"``,
``"usar_replay.missions.usar:main"``: what ``importlib`` or a ``module:function`` path loads) is a
tie like an import: an upward one fails unless :data:`STRING_TIES` lists it with the reason it
is not a dependency.

Tests mirror the package: ``usar_replay/<layer>/<module>.py`` is tested by
``tests/<layer>/test_<module>.py`` (or ``test_<module>_<aspect>.py``); a module without one is
listed in :data:`UNTESTED` with where it is tested instead (``tests/e2e/`` runs the CLI and whole
recordings, ``tests/redteam/`` attacks, ``tests/meta/`` checks the project itself).
"""

from __future__ import annotations

import ast
import graphlib
import re
import shutil
import subprocess
import sys
from pathlib import Path

PACKAGE = "usar_replay"
ROOT = Path(__file__).resolve().parents[2] / PACKAGE
TESTS = ROOT.parent / "tests"

# Each layer and the layers it may import (the package root, for __version__, is open to all).
# The order is the layers' order: a layer may import only layers listed before it.
LAYERS: dict[str, frozenset[str]] = {
    "core": frozenset(),
    "world": frozenset({"core"}),
    "log": frozenset({"core", "world"}),
    "sim": frozenset({"core", "world"}),
    "sandbox": frozenset({"core"}),
    "node": frozenset({"core", "world"}),
    "api": frozenset({"core", "world", "node"}),
    "missions": frozenset({"core", "world", "node", "api"}),
    "process": frozenset({"core", "world", "sandbox", "node"}),
    "grading": frozenset({"core", "world", "log"}),
    "pipeline": frozenset({"core", "world", "log", "sim", "sandbox", "node", "process", "grading"}),
    "ros1": frozenset(
        {"core", "world", "log", "sim", "sandbox", "node", "process", "grading", "pipeline"}
    ),
    "viewer": frozenset({"core", "world", "log", "grading"}),
    "code": frozenset({"core", "sandbox", "ros1"}),
    "batch": frozenset(
        {
            *("core", "world", "log", "sim", "sandbox", "node", "process", "grading"),
            *("pipeline", "ros1", "code"),
        }
    ),
    "cli": frozenset(
        {
            *("core", "world", "log", "sim", "sandbox", "node", "process", "api", "grading"),
            *("pipeline", "ros1", "viewer", "code", "batch"),
        }
    ),
}
# What each layer is for, for the message that says where a misplaced module belongs.
PURPOSE = {
    "core": "shared facts and codecs (messages, contract, settings, errors, tf buffer, CDR)",
    "world": "the world as data and the course's infrastructure (scenario, planner, detector)",
    "log": "the MCAP file (reading, writing, the opened run, info, recover)",
    "sim": "the pybullet simulator and its camera",
    "sandbox": "confining untrusted code (bubblewrap, cgroups v1/v2, CPU sets, run folder, guard)",
    "node": "the rclpy-shaped node API",
    "api": "the one import for mission authors",
    "missions": "the built-in missions, written on the node API",
    "process": "the mission process: usar's handle on it, its own side, the wire protocol",
    "grading": "rubrics, grades and their reports",
    "pipeline": "record and replay",
    "ros1": "a course's ROS 1 catkin package run against usar's world (build, bridge)",
    "viewer": "what rerun shows",
    "code": "the code submission graded, copies across a class, the report's flags",
    "batch": "grading a class",
    "cli": "the usar command",
}
# Layers a mission process loads: they must not import a heavy back end, even indirectly.
LIGHT_LAYERS = ("core", "world", "sandbox", "node", "api", "missions", "process")
HEAVY = ("pybullet", "mcap", "rerun")
# The one layer that may import each heavy back end.
HEAVY_HOME = {"pybullet": "sim", "mcap": "log", "rerun": "viewer"}


def _layer_of(module: str) -> str:
    """``usar_replay.world.nav`` -> ``world``; ``usar_replay.api`` -> ``api``."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def modules(root: Path = ROOT) -> dict[str, Path]:
    """Every module of the package as its dotted name (``__init__`` files included)."""
    out: dict[str, Path] = {}
    for path in sorted(root.rglob("*.py")):
        rel = path.relative_to(root.parent).with_suffix("")
        parts = list(rel.parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _is_type_checking(node: ast.If) -> bool:
    t = node.test
    return (isinstance(t, ast.Name) and t.id == "TYPE_CHECKING") or (
        isinstance(t, ast.Attribute) and t.attr == "TYPE_CHECKING"
    )


def _targets(node: ast.Import | ast.ImportFrom, mods: dict[str, Path], here: str) -> set[str]:
    """The package modules (and heavy back ends, as ``!name``) one import statement loads."""
    names: list[str] = []
    if isinstance(node, ast.Import):
        names = [a.name for a in node.names]
    else:
        if node.level:  # relative: from the module's package, up level - 1
            pkg = here.split(".") if mods[here].stem == "__init__" else here.split(".")[:-1]
            base = pkg[: len(pkg) - node.level + 1]
            module = ".".join(base + ([node.module] if node.module else []))
        else:
            module = node.module or ""
        names = [module] + [f"{module}.{a.name}" for a in node.names]
    out: set[str] = set()
    for name in names:
        top = name.split(".")[0]
        if top in HEAVY:
            out.add("!" + top)
        elif top == PACKAGE:
            # the longest prefix that is a module of ours
            parts = name.split(".")
            for n in range(len(parts), 0, -1):
                cand = ".".join(parts[:n])
                if cand in mods:
                    out.add(cand)
                    break
    return out - {here}


STRING_NAME = re.compile(rf"{PACKAGE}(\.\w+)+(:\w+)?")
"""A string literal naming a module of ours (``importlib``'s argument, a ``module:function``)."""

# Upward ties through a string that are not dependencies, each with why.
STRING_TIES: dict[tuple[str, str], str] = {
    ("usar_replay.process.worker", "usar_replay.api"): (
        "preloaded in the mission process before the audit guard is on (numpy's import needs "
        "ctypes); the mission's own code is what imports the api"
    ),
    ("usar_replay.world.assignment", "usar_replay.missions.usar"): (
        "an assignment's default mission as a module:function path (data): the process layer's "
        "loader imports it inside the mission process"
    ),
    ("usar_replay.world.assignment", "usar_replay.missions.ros2_final"): (
        "an assignment's default mission as a module:function path (data): the process layer's "
        "loader imports it inside the mission process"
    ),
    ("usar_replay.log.run", "usar_replay.missions.usar"): (
        "a label: the module a log's mission info names when the log does not say; never imported"
    ),
}


def string_ties(root: Path = ROOT) -> dict[str, set[str]]:
    """Each module's ties through string literals that name a module of ours (the longest
    dotted prefix that is one), itself left out."""
    mods = modules(root)
    out: dict[str, set[str]] = {m: set() for m in mods}
    for name, path in mods.items():
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), str(path))):
            if not (isinstance(node, ast.Constant) and isinstance(node.value, str)):
                continue
            if not STRING_NAME.fullmatch(node.value):
                continue
            parts = node.value.split(":")[0].split(".")
            for n in range(len(parts), 1, -1):
                cand = ".".join(parts[:n])
                if cand in mods:
                    out[name].add(cand)
                    break
        out[name].discard(name)
    return out


def import_graph(root: Path = ROOT) -> tuple[dict[str, set[str]], dict[str, set[str]]]:
    """(module-level edges, deferred edges): module-level imports run when the module is
    imported (class bodies and try blocks included); deferred ones are inside functions or
    under ``if TYPE_CHECKING:`` (never run). Heavy back ends appear as ``!pybullet`` etc."""
    mods = modules(root)
    top: dict[str, set[str]] = {m: set() for m in mods}
    deferred: dict[str, set[str]] = {m: set() for m in mods}

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
                (deferred if d else top)[name].update(_targets(child, mods, name))
            visit(child, name, d)

    for name, path in mods.items():
        visit(ast.parse(path.read_text(encoding="utf-8"), str(path)), name, False)
    return top, deferred


def _allowed_for(layer: str) -> str:
    return ", ".join(sorted(LAYERS[layer])) or "nothing of usar's"


def _homes_for(needs: str) -> str:
    """The layers that may import ``needs``: where a module needing it belongs."""
    return ", ".join(k for k, v in LAYERS.items() if needs in v or k == needs)


def violations(root: Path = ROOT) -> list[str]:
    """Every broken layer rule, one line each, saying where the module belongs."""
    top, deferred = import_graph(root)
    strings = string_ties(root)
    out: list[str] = []
    for mod in sorted(top):
        layer = _layer_of(mod)
        rel = modules(root)[mod].relative_to(root.parent)
        if mod == PACKAGE:
            continue
        if layer not in LAYERS:
            out.append(
                f"{rel} is in no layer: put it in one of "
                + ", ".join(f"{k}/ ({v})" for k, v in PURPOSE.items() if k not in ("api",))
            )
            continue
        for dep in sorted(top[mod] | deferred[mod]):
            if dep.startswith("!"):
                lib = dep[1:]
                if HEAVY_HOME[lib] != layer and layer != "cli":
                    out.append(
                        f"{rel} imports {lib}: only {HEAVY_HOME[lib]}/ may import it; move the "
                        f"code that needs {lib} into {HEAVY_HOME[lib]}/"
                    )
                continue
            dep_layer = _layer_of(dep)
            if dep == PACKAGE or dep_layer == layer:
                continue
            if dep_layer not in LAYERS[layer]:
                out.append(
                    f"{rel} imports {dep}: the {layer} layer may import only {_allowed_for(layer)};"
                    f" a module that needs {dep_layer} belongs in {_homes_for(dep_layer)}"
                )
        for dep in sorted(strings[mod]):
            dep_layer = _layer_of(dep)
            if dep_layer in (layer, "") or dep_layer in LAYERS[layer]:
                continue
            if (mod, dep) not in STRING_TIES:
                out.append(
                    f"{rel} names {dep} in a string (an import by name): the {layer} layer may "
                    f"import only {_allowed_for(layer)}; move the code that loads it into "
                    f"{_homes_for(dep_layer)}, or list the tie in STRING_TIES with why"
                )
    return out


def _cycle(graph: dict[str, set[str]]) -> list[str]:
    try:
        graphlib.TopologicalSorter(graph).prepare()
    except graphlib.CycleError as e:
        return list(e.args[1])
    return []


def _ours(graph: dict[str, set[str]]) -> dict[str, set[str]]:
    return {m: {d for d in ds if not d.startswith("!")} for m, ds in graph.items()}


def test_the_graph_reader_sees_imports() -> None:
    """A guard against a reader that finds nothing (and so no cycles, no violations)."""
    top, deferred = import_graph()
    assert "usar_replay.core.msgs" in top["usar_replay.core.tf_tree"]
    assert "usar_replay.core.rotations" in top["usar_replay.world.nav"]
    assert "!pybullet" in top["usar_replay.sim.simulator"]
    assert sum(len(v) for v in top.values()) > 100
    assert any(deferred.values())  # the cli imports its commands lazily


def test_every_module_sits_in_a_layer_and_imports_only_the_layers_below() -> None:
    problems = violations()
    assert problems == [], "layer rules broken:\n" + "\n".join(problems)


def test_a_misplaced_module_fails_with_where_it_belongs(tmp_path: Path) -> None:
    """A copy of the package with three deliberate mistakes: each is named, with a fix."""
    copy = tmp_path / PACKAGE
    shutil.copytree(ROOT, copy, ignore=shutil.ignore_patterns("__pycache__"))
    (copy / "world" / "misplaced.py").write_text(
        "from usar_replay.log.bag import BagReader\n", encoding="utf-8"
    )
    (copy / "core" / "heavy.py").write_text(
        "def f() -> None:\n    import pybullet\n", encoding="utf-8"
    )
    (copy / "stray.py").write_text("X = 1\n", encoding="utf-8")
    problems = violations(copy)
    assert len(problems) == 3, problems
    world, heavy, stray = (
        next(p for p in problems if p.startswith(f"{PACKAGE}/{f}")) for f in (
            "world/misplaced.py", "core/heavy.py", "stray.py"
        )
    )
    assert "the world layer may import only core" in world
    assert "belongs in log, grading, pipeline, ros1, viewer, batch, cli" in world
    assert "only sim/ may import it" in heavy
    assert "is in no layer" in stray and "world/" in stray


def test_a_string_that_names_a_module_is_an_import(tmp_path: Path) -> None:
    """``importlib.import_module("usar_replay.cli.main")`` in core, or a ``module:function``
    path naming grading in world, breaks the layers like an import would."""
    copy = tmp_path / PACKAGE
    shutil.copytree(ROOT, copy, ignore=shutil.ignore_patterns("__pycache__"))
    (copy / "core" / "loader.py").write_text(
        "import importlib\n\n\ndef f() -> object:\n"
        "    return importlib.import_module('usar_replay.cli.main')\n",
        encoding="utf-8",
    )
    (copy / "world" / "plugin.py").write_text(
        "GRADER = 'usar_replay.grading.grade:grade_file'\nNOT_A_MODULE = 'usar_replay is great'\n",
        encoding="utf-8",
    )
    problems = violations(copy)
    assert len(problems) == 2, problems
    core, world = sorted(problems)
    assert core.startswith(f"{PACKAGE}/core/loader.py names usar_replay.cli.main in a string")
    assert "the core layer may import only nothing of usar's" in core
    assert world.startswith(f"{PACKAGE}/world/plugin.py names usar_replay.grading.grade")
    # the listed ties are seen too: unlisted, each is a violation
    assert all(dep in string_ties(copy)[mod] for mod, dep in STRING_TIES)


def test_every_listed_string_tie_is_still_there() -> None:
    """STRING_TIES cannot rot: each entry names a tie the tree still has."""
    ties = string_ties()
    stale = [f"{m} -> {d}" for m, d in STRING_TIES if d not in ties[m]]
    assert stale == [], f"STRING_TIES lists ties that are gone: {stale}"


def test_no_cycles_among_module_level_imports() -> None:
    top, _ = import_graph()
    cyc = _cycle(_ours(top))
    assert cyc == [], f"import cycle at module level: {' -> '.join(cyc)}"


def test_no_cycles_counting_deferred_imports_too() -> None:
    """Also the imports inside functions and under TYPE_CHECKING: a cycle there is a design
    smell (two modules that each need the other), even when import order hides it."""
    top, deferred = import_graph()
    both = _ours({m: top[m] | deferred[m] for m in top})
    cyc = _cycle(both)
    assert cyc == [], f"import cycle (with deferred imports): {' -> '.join(cyc)}"


# Modules with no tests/<layer>/test_<module>.py, and where they are tested instead.
UNTESTED: dict[str, str] = {
    "batch/engines.py": "tests/batch/test_driver.py runs the local pool and Ray on one class",
    "batch/run_one.py": "the job a batch engine runs: tests/batch/test_driver.py grades classes",
    "cli/commands/batch.py": "tests/batch/test_driver.py runs `usar batch`",
    "cli/commands/replay.py": "tests/e2e/test_tour.py and tests/e2e/test_examples.py run it",
    "process/worker.py": (
        "the mission's side: tests/process/test_mission_process.py (handshake, verdicts), "
        "tests/node/test_node.py (crash, hang, memory)"
    ),
    "ros1/process.py": "covered end to end by tests/e2e/test_ros1.py",
}


def missing_tests(root: Path = ROOT, tests: Path = TESTS) -> list[str]:
    """Each module with no ``tests/<layer>/test_<module>.py`` (or ``test_<module>_*.py``) that
    :data:`UNTESTED` does not list, one line each, saying what to add."""
    out: list[str] = []
    for path in sorted(root.rglob("*.py")):
        if path.name == "__init__.py":
            continue
        rel = path.relative_to(root)
        folder = tests / rel.parent
        if (folder / f"test_{path.stem}.py").is_file() or any(
            folder.glob(f"test_{path.stem}_*.py")
        ):
            continue
        if rel.as_posix() not in UNTESTED:
            want = (Path("tests") / rel.parent / f"test_{path.stem}.py").as_posix()
            out.append(
                f"{PACKAGE}/{rel.as_posix()} has no test file: add {want}, or list the module "
                "in UNTESTED with where it is tested"
            )
    return out


def test_every_module_has_a_test_file_or_a_reason() -> None:
    problems = missing_tests()
    assert problems == [], "\n".join(problems)


def test_untested_lists_only_modules_without_a_test_file() -> None:
    """A module that gains its test file, or is gone, leaves UNTESTED; every reason names the
    test that covers the module, and that test exists."""
    for key, reason in UNTESTED.items():
        path = ROOT / key
        assert path.is_file(), f"UNTESTED lists {key}, which is gone"
        folder = TESTS / Path(key).parent
        assert not (folder / f"test_{path.stem}.py").is_file(), f"{key} has a test file now"
        for named in re.findall(r"tests/[\w/]+\.py", reason):
            assert (ROOT.parent / named).is_file(), f"UNTESTED[{key!r}] names {named}: none"


def test_a_module_without_a_test_file_is_named(tmp_path: Path) -> None:
    copy = tmp_path / PACKAGE
    shutil.copytree(ROOT, copy, ignore=shutil.ignore_patterns("__pycache__"))
    (copy / "world" / "orphan.py").write_text("X = 1\n", encoding="utf-8")
    problems = missing_tests(copy, TESTS)
    assert problems == [
        f"{PACKAGE}/world/orphan.py has no test file: add tests/world/test_orphan.py, or list "
        "the module in UNTESTED with where it is tested"
    ]
    (tmp_path / "tests" / "world").mkdir(parents=True)
    (tmp_path / "tests" / "world" / "test_orphan_edges.py").write_text("", encoding="utf-8")
    assert "world/orphan.py" not in " ".join(missing_tests(copy, tmp_path / "tests"))


def test_every_init_only_says_and_re_exports() -> None:
    """An ``__init__.py`` needs no test file of its own because it defines nothing."""
    for path in sorted(ROOT.rglob("__init__.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"))
        defs = [n for n in tree.body if isinstance(n, ast.FunctionDef | ast.ClassDef)]
        assert defs == [], f"{path} defines {[d.name for d in defs]}: give them a module"


LIGHT_MODULES = sorted(m for m in modules() if _layer_of(m) in LIGHT_LAYERS)


def test_every_layer_has_an_init_that_says_what_it_is() -> None:
    for layer in LAYERS:
        init = ROOT / layer / "__init__.py"
        if layer in ("api",):
            continue
        assert init.is_file(), f"{layer}/ has no __init__.py"
        doc = ast.get_docstring(ast.parse(init.read_text(encoding="utf-8"))) or ""
        assert doc.startswith(f"{layer}:"), f"{init} must open with '{layer}: what it is'"
        assert "import" in doc, f"{init} must say what the layer may import"


def test_the_light_layers_load_no_heavy_back_end() -> None:
    """Every module a mission process may load, imported in a fresh interpreter, leaves none
    of pybullet, mcap, rerun in ``sys.modules`` (one interpreter per module: an import that
    pulls a back end in indirectly is caught where it starts)."""
    assert len(LIGHT_MODULES) > 20
    code = (
        "import sys, importlib\n"
        "bad = {}\n"
        "for m in sys.argv[1:]:\n"
        "    before = {k.split('.')[0] for k in sys.modules}\n"
        "    importlib.import_module(m)\n"
        f"    new = {{k.split('.')[0] for k in sys.modules}} & set({HEAVY!r})\n"
        "    if new: bad[m] = sorted(new)\n"
        "print(bad)\n"
    )
    # each module alone (a shared interpreter would hide who loaded it first)
    for mod in LIGHT_MODULES:
        out = subprocess.run(
            [sys.executable, "-c", code, mod], capture_output=True, text=True, check=True,
            timeout=120,
        )
        assert out.stdout.strip() == "{}", f"{mod} loads {out.stdout.strip()}"


def test_the_package_ships_py_typed() -> None:
    """PEP 561: the marker file exists and the build lists it as package data."""
    import tomllib

    assert (ROOT / "py.typed").is_file()
    project = tomllib.loads((ROOT.parent / "pyproject.toml").read_text(encoding="utf-8"))
    assert "py.typed" in project["tool"]["setuptools"]["package-data"][PACKAGE]


def test_every_folder_is_a_package() -> None:
    """setuptools ships only folders with an ``__init__.py``: a layer without one would be
    left out of the wheel."""
    for folder in sorted({p.parent for p in ROOT.rglob("*.py")}):
        assert (folder / "__init__.py").is_file(), f"{folder} has no __init__.py"
