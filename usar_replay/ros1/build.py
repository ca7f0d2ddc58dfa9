"""A private catkin workspace: usar's ``fiducial_msgs`` next to a copy of the package, built.

Why a copy in a temporary workspace: the student's folder is never written to (no ``build/``
or ``devel/`` left behind, a read-only checkout works), and the workspace holds exactly two
packages, so nothing else on the machine can change the build. A build that fails is the
*package's* outcome, ``build_failed`` with the compiler's errors, recorded in the log like a
crash; never a traceback of usar's.

catkin_make runs as Debian's own program with a clean environment (``PATH=/usr/bin:/bin``,
``PYTHON_EXECUTABLE=/usr/bin/python3``): a virtual environment's or pyenv's ``python3`` on the
PATH has no ``catkin_pkg``, and catkin would pick it up.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

from usar_replay.core.errors import UsageError
from usar_replay.node.worker import MissionEnded

__all__ = [
    "FIDUCIAL_MSGS",
    "Built",
    "Package",
    "build",
    "cache_root",
    "cached_build",
    "find_package",
    "package_sha256",
]

FIDUCIAL_MSGS = Path(__file__).resolve().parent / "catkin" / "fiducial_msgs"
"""aruco_detect's message package, as usar ships it (Debian has no fiducials)."""

_NAME = re.compile(r"<name>\s*([A-Za-z0-9_]+)\s*</name>")
_SKIP = {"build", "devel", "install", ".git", "__pycache__", "log", "logs"}


@dataclass(frozen=True, slots=True)
class Package:
    """A catkin package folder (one ``package.xml``)."""

    path: Path
    name: str


@dataclass(frozen=True, slots=True)
class Built:
    """A built workspace."""

    workspace: Path
    package: Package
    seconds: float
    """Wall seconds catkin_make took (0 for a build found in the cache)."""
    cached: bool = False

    @property
    def setup(self) -> Path:
        return self.workspace / "devel" / "setup.bash"


def find_package(path: str | os.PathLike[str]) -> Package:
    """The catkin package at ``path``: a folder with ``package.xml``, or a workspace ``src/``
    (or any folder) holding exactly one package other than ``fiducial_msgs``."""
    root = Path(path)
    if not root.is_dir():
        raise UsageError(f"--ros1 {path}: no such folder (give a catkin package folder)")
    found = [root / "package.xml"] if (root / "package.xml").is_file() else []
    if not found:
        found = sorted(p for p in root.glob("*/package.xml") if p.parent.name != "fiducial_msgs")
        found = found or sorted(root.glob("*/*/package.xml"))
    if len(found) != 1:
        what = "no package.xml" if not found else f"{len(found)} packages"
        raise UsageError(f"--ros1 {path}: {what} found; give one catkin package folder")
    match = _NAME.search(found[0].read_text(encoding="utf-8", errors="replace"))
    if match is None:
        raise UsageError(f"--ros1 {path}: {found[0]} has no <name>")
    return Package(found[0].parent, match.group(1))


def _files(root: Path) -> list[Path]:
    out = []
    for p in sorted(root.rglob("*")):
        rel = p.relative_to(root)
        if p.is_file() and not p.is_symlink() and not (set(rel.parts[:-1]) & _SKIP):
            out.append(p)
    return out


def package_sha256(pkg: Package) -> str:
    """sha256 over the package's files (relative path and bytes, in sorted order): the log
    says exactly which code ran (build outputs and ``.git`` left out)."""
    h = hashlib.sha256()
    for p in _files(pkg.path):
        rel = p.relative_to(pkg.path).as_posix().encode()
        data = p.read_bytes()
        h.update(len(rel).to_bytes(8, "little") + rel + len(data).to_bytes(8, "little") + data)
    return h.hexdigest()


def _copy(pkg: Package, dest: Path) -> None:
    for p in _files(pkg.path):
        target = dest / p.relative_to(pkg.path)
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(p, target)


def _errors(output: str, limit: int = 60) -> str:
    """The compiler's and CMake's errors from catkin_make's output (the lines that say what is
    wrong and the ones after), or its last lines when none is marked."""
    lines = output.splitlines()
    keep: list[str] = []
    for i, line in enumerate(lines):
        if re.search(r"error|Error|ERROR", line):
            keep += lines[i : i + 3]
    picked = list(dict.fromkeys(keep)) or lines[-limit:]
    return "\n".join(picked[:limit])


def _sandboxed(cmd: list[str], workspace: Path) -> tuple[list[str], dict[str, str]]:
    """``cmd`` in the kernel sandbox when there is one: a package's CMakeLists.txt runs
    whatever it likes at build time (``execute_process``), so the build is the student's code
    too. It reads the system and Debian's ROS configuration, writes only the workspace, and has
    no network. Without bubblewrap (or with ``USAR_SANDBOX=off``) it runs as it is, as a
    mission does then."""
    from usar_replay.node import kernel_sandbox

    ok, _ = kernel_sandbox.bwrap_available()
    if not ok or os.environ.get("USAR_SANDBOX", "").strip().lower() == "off":
        return cmd, catkin_env()
    env = {"PATH": "/usr/bin:/bin", "HOME": "/tmp", "TMPDIR": "/tmp", "LANG": "C.UTF-8"}
    # catkin picks Debian's Python layout (dist-packages) by /etc/debian_version
    etc = [p for p in ("/etc/catkin", "/etc/ros", "/etc/debian_version") if Path(p).exists()]
    argv = kernel_sandbox.jail_argv(cmd, ro_binds=etc, work_dir=str(workspace), env=env)
    return argv, env


def catkin_env() -> dict[str, str]:
    """The environment catkin and roslaunch run in: Debian's tools first, no venv Python."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PATH"] = "/usr/bin:/bin:" + env.get("PATH", "")
    env.setdefault("HOME", "/tmp")
    return env


def build(pkg: Package, workspace: Path, jobs: int = 2, timeout_s: float = 900.0) -> Built:
    """Copy ``pkg`` and usar's fiducial_msgs into ``workspace/src`` and run catkin_make.

    A failure raises :class:`MissionEnded` ``build_failed`` with the compiler's errors."""
    src = workspace / "src"
    src.mkdir(parents=True, exist_ok=True)
    if pkg.name != "fiducial_msgs":
        shutil.copytree(FIDUCIAL_MSGS, src / "fiducial_msgs")
    _copy(pkg, src / pkg.name)
    cmd = ["catkin_make", "-C", str(workspace), "-DPYTHON_EXECUTABLE=/usr/bin/python3"]
    cmd += [f"-j{jobs}"]  # no -l: on a shared machine a load limit stalls the build
    start = time.perf_counter()  # for the build time shown to people only
    argv, env = _sandboxed(cmd, workspace)
    try:
        proc = subprocess.run(
            argv,
            cwd=workspace,
            env=env,
            stdin=subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            timeout=timeout_s,
            check=False,
        )
    except subprocess.TimeoutExpired as err:
        raise MissionEnded(
            "build_failed", f"catkin_make took more than {timeout_s:g} s of wall time"
        ) from err
    output = proc.stdout.decode("utf-8", errors="replace")
    (workspace / "build.log").write_text(output, encoding="utf-8")
    if proc.returncode != 0:
        raise MissionEnded(
            "build_failed",
            f"catkin_make failed (exit {proc.returncode}) for package {pkg.name}:\n"
            + _errors(output)
            + f"\ncatkin_make failed for package {pkg.name}",
        )
    return Built(workspace, pkg, time.perf_counter() - start)


def cache_root() -> Path:
    """Where built workspaces are kept: ``$XDG_CACHE_HOME/usar/ros1`` (``~/.cache/...``)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "usar" / "ros1"


def _build_key(pkg: Package) -> str:
    """Same package files, same fiducial_msgs, same usar, same compiler: the same build."""
    from usar_replay import __version__

    h = hashlib.sha256()
    h.update(package_sha256(pkg).encode())
    h.update(package_sha256(Package(FIDUCIAL_MSGS, "fiducial_msgs")).encode())
    h.update(__version__.encode())
    h.update(str(shutil.which("g++")).encode())
    return f"{pkg.name}-{h.hexdigest()[:20]}"


def cached_build(pkg: Package, root: Path | None = None) -> Built:
    """:func:`build` once per package content: a workspace built before (same files, same
    fiducial_msgs, same usar) is reused as it is, read only. Why: catkin_make costs ~40 s of
    CPU, and a class's runs (or a test's variants of one package) build the same files. The
    workspace is built in place (catkin writes absolute paths into ``devel/``), under a lock so
    that two runs never build one key at once; a failed build is not kept."""
    import fcntl

    root = root or cache_root()
    root.mkdir(parents=True, exist_ok=True)
    key = _build_key(pkg)
    ws = root / key
    with (root / f"{key}.lock").open("w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if (ws / ".usar-built").is_file():
            return Built(ws, pkg, 0.0, cached=True)
        shutil.rmtree(ws, ignore_errors=True)
        try:
            built = build(pkg, ws)
        except BaseException:
            shutil.rmtree(ws, ignore_errors=True)
            raise
        (ws / ".usar-built").write_text(f"{built.seconds:.1f}\n", encoding="utf-8")
        return built
