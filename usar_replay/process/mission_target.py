"""What ``--mission`` names, checked in usar's process and loaded in the mission's.

Why a module of its own: the recorder resolves the target (a :class:`UsageError` before any
work; the source's sha256 goes into the log, so the log says exactly which code ran), and the
mission process (:mod:`usar_replay.process.worker`) loads it, in the kernel sandbox, from the same
:class:`MissionTarget`. A target is a reference mission's name (``builtin``, an assignment's), a
``.py`` file (``team7/mission.py``, optionally ``:function``) or ``module:function``.
"""

from __future__ import annotations

import hashlib
import importlib
import importlib.util
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

from usar_replay.core.errors import UsageError

__all__ = ["BUILTIN", "FILE_MODULE", "MissionTarget", "load", "resolve_target"]

BUILTIN = "builtin"
"""``--mission builtin`` (the default): the course's reference mission."""

FILE_MODULE = "usar_user_mission"
"""The module name a ``.py`` file target is loaded under."""


@dataclass(frozen=True, slots=True)
class MissionTarget:
    """What ``--mission`` named: a built-in name, a ``.py`` file, or ``module:attribute``."""

    spec: str
    """As the user gave it (``builtin``, ``team7/mission.py``, ``my_pkg.mission:main``)."""
    module: str
    """The module to import (a file's is loaded under the name :data:`FILE_MODULE`)."""
    attribute: str
    """The callable that creates the nodes (default ``main``)."""
    path: str
    """The source file ('' when the module is not a file)."""
    sha256: str
    """sha256 of the source file: the log says exactly which code ran."""

    @property
    def is_file(self) -> bool:
        """A ``.py`` file given by its path (not a module found on ``sys.path``)."""
        return self.module == FILE_MODULE

    @property
    def is_usar_module(self) -> bool:
        """One of usar's own modules (a reference mission)."""
        return self.module.startswith("usar_replay.")

    def module_root(self) -> str:
        """The folder a module target was found under (its top package's parent; '' when
        unknown)."""
        if not self.path:
            return ""
        path = Path(self.path)
        depth = self.module.count(".") + (2 if path.name == "__init__.py" else 1)
        return str(path.parents[depth - 1]) if len(path.parents) >= depth else ""

    def submission_roots(self) -> list[str]:
        """What the sandboxed mission reads by default: its file's folder (helpers next to it),
        or the folder its module was found in; nothing for usar's own missions (bound with
        usar's package, whose parent may be a whole checkout)."""
        if self.is_file:
            return [str(Path(self.path).parent)]
        if self.is_usar_module:
            return []
        root = self.module_root()
        return [root] if root else []


def resolve_target(spec: str | None) -> MissionTarget:
    """Check ``--mission`` and find its source (a :class:`UsageError` says what is wrong)."""
    spec = (spec or BUILTIN).strip()
    if spec.startswith("ros1:"):
        raise UsageError(
            f"mission {spec!r} is a ROS 1 package: only Python missions are re-run here; "
            "grade its recorded outputs with usar grade, or record it again with --ros1"
        )
    # a reference mission's name (builtin, an assignment's): the assignment's module:function
    from usar_replay.world.assignment import mission_path

    text = mission_path(spec) or spec
    attr = "main"
    if text.endswith(".py") or "/" in text or os.sep in text:
        file_part = text
        if ":" in text and not text.endswith(".py"):
            file_part, attr = text.rsplit(":", 1)
        path = Path(file_part)
        if not path.is_file():
            raise UsageError(f"--mission {spec}: no such file; give a .py file or module:function")
        source = path.read_bytes()
        return MissionTarget(
            spec, FILE_MODULE, attr, str(path.resolve()), hashlib.sha256(source).hexdigest()
        )
    module, _, attr_part = text.partition(":")
    attr = attr_part or "main"
    try:
        found = importlib.util.find_spec(module)
    except (ImportError, ValueError):
        found = None
    if found is None or found.origin is None:
        raise UsageError(
            f"--mission {spec}: cannot find module {module!r}; give a .py file or module:function"
        )
    origin = found.origin
    digest = hashlib.sha256(Path(origin).read_bytes()).hexdigest() if Path(origin).is_file() else ""
    return MissionTarget(spec, module, attr, origin, digest)


def load(target: MissionTarget) -> ModuleType:
    """Import the target's module (a file's under :data:`FILE_MODULE`, its folder first on
    ``sys.path`` so helpers next to it import): in the mission process, never in usar's. What
    the module raises is the mission's own error."""
    if target.is_file:
        spec = importlib.util.spec_from_file_location(target.module, target.path)
        if spec is None or spec.loader is None:
            raise ImportError(f"cannot load {target.path}")
        module = importlib.util.module_from_spec(spec)
        sys.modules[target.module] = module
        sys.path.insert(0, str(Path(target.path).parent))
        spec.loader.exec_module(module)
        return module
    return importlib.import_module(target.module)
