"""One error hierarchy: every usar error is defined in core/errors.py under ``UsarError``.

The check reads the package's source (no imports: pybullet and rerun stay unloaded). An
exception class defined anywhere else must be one of the few listed below, each with the reason
it is not a ``UsarError`` (an API mirror for mission code, or control flow inside one module).
"""

from __future__ import annotations

import ast
import builtins
from pathlib import Path

import pytest

from usar_replay.core import errors

PACKAGE = Path(__file__).resolve().parents[2] / "usar_replay"

NOT_USAR_ERRORS = {
    "core/tf_tree.py": {
        "TransformException": "tf2's exception family, mirrored for mission code",
        "LookupException": "tf2's",
        "ConnectivityException": "tf2's",
        "ExtrapolationException": "tf2's",
        "InvalidArgumentException": "tf2's",
        "TimeoutException": "tf2's",
    },
    "node/node.py": {"ParameterNotDeclared": "rclpy's exception, raised in mission code"},
    "sandbox/audit_guard.py": {
        "GuardViolation": "raised in the mission's own code (a PermissionError)"
    },
    "node/boundary_check.py": {
        "OutputRefused": "turned into the verdict `refused` (MissionEnded) by the mission process",
        "PublishRefused": "raised in the mission's own code (a PermissionError)",
    },
    "log/mcapfile.py": {"Broken": "caught inside mcapfile: becomes a Damage report"},
    "core/cdrdecode.py": {
        "Unsupported": "caught by the reader: falls back to rosbags",
        "_Unknown": "private control flow",
    },
    "core/msg_text.py": {"FieldPathError": "caught by log/echo: becomes a UsageError"},
    "core/finite.py": {"NonFiniteValue": "caught at the process boundary: a refused output"},
    "core/signals.py": {"Terminated": "a KeyboardInterrupt: how the CLI and batch stop"},
    "batch/run_one.py": {
        "WallLimit": "a KeyboardInterrupt: how a batch run stops",
        "GradeStopped": "a BaseException: stops grading at its limit, past any `except`",
    },
}

_BUILTIN_ROOTS = {"Exception", "BaseException", "KeyboardInterrupt"}


def _exception_classes() -> dict[tuple[str, str], list[str]]:
    """(module path, class name) -> base names, for every class whose bases look like an
    exception (a builtin exception, or a class already known to be one)."""
    known = set(_BUILTIN_ROOTS) | {n for n in dir(builtins) if n.endswith("Error")}
    known |= {n for n in dir(errors) if isinstance(getattr(errors, n), type)}
    found: dict[tuple[str, str], list[str]] = {}
    trees = {
        str(p.relative_to(PACKAGE)): ast.parse(p.read_text(encoding="utf-8"))
        for p in sorted(PACKAGE.rglob("*.py"))
    }
    changed = True
    while changed:  # classes derived from an exception defined in another module
        changed = False
        for rel, tree in trees.items():
            for node in ast.walk(tree):
                if not isinstance(node, ast.ClassDef) or (rel, node.name) in found:
                    continue
                bases = [ast.unparse(b).rsplit(".", 1)[-1] for b in node.bases]
                if any(b in known for b in bases):
                    found[(rel, node.name)] = bases
                    known.add(node.name)
                    changed = True
    return found


def test_every_usar_error_is_defined_in_core_errors() -> None:
    usar = {n for n in dir(errors) if isinstance(getattr(errors, n), type)}
    strays = [
        f"{rel}: {name}({', '.join(bases)})"
        for (rel, name), bases in _exception_classes().items()
        if rel != "core/errors.py" and NOT_USAR_ERRORS.get(rel, {}).get(name) is None
    ]
    assert not strays, f"define these in core/errors.py (under UsarError): {strays}"
    for name in errors.__all__:
        assert name in usar
        assert issubclass(getattr(errors, name), errors.UsarError)


@pytest.mark.parametrize(
    ("module", "name"),
    [
        ("usar_replay.process.mission_process", "MissionEnded"),
        ("usar_replay.world.detect", "DetectError"),
        ("usar_replay.ros1.building.debian", "MissingRos1"),
    ],
)
def test_moved_errors_are_importable_where_they_are_raised(module: str, name: str) -> None:
    import importlib

    cls = getattr(importlib.import_module(module), name)
    assert cls is getattr(errors, name)
    assert issubclass(cls, errors.UsarError)


def test_the_allow_list_names_classes_that_exist() -> None:
    defined = set(_exception_classes())
    listed = {(rel, name) for rel, names in NOT_USAR_ERRORS.items() for name in names}
    assert listed <= defined, sorted(listed - defined)
