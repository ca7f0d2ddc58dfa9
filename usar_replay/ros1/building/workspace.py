"""Private catkin workspaces: usar's packages as an underlay, the package in an overlay.

Why an underlay: a course machine has ``fiducial_msgs`` installed (built before the student's
package, in another workspace), so a package's ``CMakeLists.txt`` that builds there builds here
as it is: no ``add_dependencies(... ${catkin_EXPORTED_TARGETS})`` needed for usar's messages.
The underlay also holds usar's stand-ins for what a course machine has and usar replaces
(gazebo_ros, turtlebot3's, amcl, move_base, ...: :mod:`.standins`), so ``find_package`` and
``$(find X)`` of those names resolve.
The underlay is usar's own bytes, built once (in the sandbox all the same) and shared; the
overlay holds a copy of the package alone, so the student's folder is never written to and
nothing else on the machine can change the build.

Why so careful with what the build leaves (issue 26): the build is the team's code
(``execute_process`` at configure time) and runs as such (:mod:`usar_replay.ros1.building.jail`).
usar writes nothing into the workspace the build can write: the build's output comes through a
pipe, and what usar keeps about a build (its manifest, its time) lives in the workspace's
parent folder, which no sandbox ever binds, created ``O_EXCL|O_NOFOLLOW``. Once the sandbox is
gone the workspace is checked (no link out of it, no special file), frozen read-only and listed
(:mod:`usar_replay.ros1.building.tree`); a run mounts it read-only, and a cached build is verified
against its manifest before it is reused. A build that fails, or goes past a limit, is the
*package's* outcome, ``build_failed`` with the compiler's errors (paths in the student's
folder) and a hint; never a traceback of usar's.

In the sandbox the package's workspace is built at ``/ros1/ws`` and the underlay at
``/ros1/underlay``, whatever host folders hold them, so that nothing the build writes (catkin's
absolute paths, a node's ``__FILE__`` in its ``/rosout`` lines) depends on the host
(:mod:`usar_replay.ros1.building.layout`).

catkin_make runs as Debian's own program with a clean environment (``PATH=/usr/bin:/bin``,
``PYTHON_EXECUTABLE=/usr/bin/python3``): a virtual environment's or pyenv's ``python3`` on the
PATH has no ``catkin_pkg``, and catkin would pick it up.

Why a package's build is given ``-Wall -Wextra`` (:data:`WARNING_FLAGS`, the initial
``CMAKE_CXX_FLAGS``, so the package's own flags come after them and win) and its output is
kept (:attr:`Built.output`, with the cache entry for a cached build): ``usar batch --code``
scores "builds without warnings" from the demo's own build (:mod:`usar_replay.code.compile`).
Warning options change no generated code; a package whose CMake files ask for ``-Werror``
(which would turn them into a failed build) is built with its own flags alone.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import os
import re
import shutil
import stat
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import usar_replay.ros1.building.layout as layout
import usar_replay.ros1.building.message as buildmsg
import usar_replay.ros1.building.standins as standins
import usar_replay.ros1.building.tree as tree
from usar_replay.core.errors import (
    BuildFailed,
    MissionEnded,
    NoPackage,
    SeveralPackages,
    UnusableSubmission,
    UsageError,
)
from usar_replay.core.folder_walk import Entry, shown, stream, walk
from usar_replay.ros1.building.build_folder import BuildFolder
from usar_replay.ros1.building.jail import BuildLimits, run_jailed

__all__ = [
    "FIDUCIAL_MSGS",
    "WARNING_FLAGS",
    "BuildFailed",
    "BuildLimits",
    "Built",
    "NoPackage",
    "SeveralPackages",
    "Package",
    "build",
    "cache_root",
    "cached_build",
    "catkin_env",
    "find_package",
    "package_sha256",
    "private_build",
    "remove_tree",
    "sandboxed",
    "underlay",
    "warning_flags",
]

FIDUCIAL_MSGS = standins.FIDUCIAL_MSGS
"""aruco_detect's message package, as usar ships it (Debian has no fiducials)."""
PACING = standins.PACING
"""usar's pacing shim, preloaded into the package's nodes (:mod:`usar_replay.ros1.pacing.shim`)."""

_NAME = re.compile(r"<name>\s*([A-Za-z0-9_]+)\s*</name>")
_SKIP = frozenset({"build", "devel", "install", ".git", "__pycache__", "log", "logs"})
"""Folders never read from a package: catkin's outputs (committed in many student
repositories), version control, caches."""
_RECORD = "built.json"
"""Beside ``ws/``: the manifest of the built workspace, its build time and catkin_make's output
(usar's alone)."""
WARNING_FLAGS = ("-Wall", "-Wextra")
"""What a package's build is given (``CMAKE_CXX_FLAGS``), unless it asks for ``-Werror``: the
warnings ``usar code --compile`` turns on."""
_WERROR = re.compile(r"-Werror(?![=\w-])|COMPILE_WARNING_AS_ERROR")
"""Warnings made errors in a CMake file (``-Werror=x`` makes only that one an error)."""


@dataclass(frozen=True, slots=True)
class Package:
    """A catkin package folder (one ``package.xml``)."""

    path: Path
    name: str


@dataclass(frozen=True, slots=True)
class Built:
    """A built workspace (``entry/ws``), checked and frozen."""

    workspace: Path
    package: Package
    seconds: float
    """Wall seconds catkin_make took (0 for a build found in the cache)."""
    cached: bool = False
    underlays: tuple[Path, ...] = field(default=())
    """Workspaces this one extends (sourced by its ``devel/setup.bash``): usar's messages."""
    at: str = ""
    """Where it was built inside the sandbox and must be mounted to run
    (:data:`usar_replay.ros1.building.layout.WORKSPACE`, its underlays at theirs); '': at its
    host path
    (built without a kernel sandbox)."""
    output: str = ""
    """catkin_make's output (stdout and stderr) as the build printed it, paths as the build saw
    them (:attr:`source_root`); a cached build's as it was kept with the entry."""
    flags: tuple[str, ...] = ()
    """The warning flags usar added to the build (:data:`WARNING_FLAGS`, or none)."""

    @property
    def source_root(self) -> str:
        """The package's folder as its build saw it: compiler lines under it are the team's."""
        return f"{self.run_workspace}/src/{self.package.name}"

    @property
    def setup(self) -> Path:
        return self.workspace / "devel" / "setup.bash"

    @property
    def run_workspace(self) -> str:
        """The workspace's path as the run sees it."""
        return self.at or str(self.workspace)

    @property
    def run_underlays(self) -> tuple[str, ...]:
        """The underlays' paths as the run sees them."""
        if self.at:
            return tuple(layout.underlay_at(i) for i in range(len(self.underlays)))
        return tuple(map(str, self.underlays))

    @property
    def mounts(self) -> tuple[tuple[str, str], ...]:
        """(host folder, path in the sandbox) for a run to mount read-only; () when built at
        its host path (then the run binds the host folders where they are)."""
        if not self.at:
            return ()
        return ((str(self.workspace), self.at), *layout.mounts(self.underlays))


_FOUND_MAX = 4000
"""Folders :func:`find_package` looks into before it gives up (a repository, not a disk)."""
_DEPTH = 5
"""How deep a package may lie in the folder given (``repo/catkin_ws/src/group/pkg``)."""
_ADD_EXECUTABLE = re.compile(r"^[^#\n]*\badd_executable\s*\(", re.MULTILINE | re.IGNORECASE)


def _package_dirs(root: Path) -> list[Path]:
    """The catkin packages under ``root`` as catkin finds them: a folder with ``package.xml``
    is a package (not looked into further); catkin's outputs (``build/``, ``devel/``,
    ``install/``, committed with the sources in many student repositories), hidden folders,
    links and folders holding ``CATKIN_IGNORE`` are skipped."""
    found: list[Path] = []
    stack = [(root, 0)]
    seen = 0
    while stack:
        folder, depth = stack.pop()
        seen += 1
        if seen > _FOUND_MAX:
            break
        try:
            with os.scandir(folder) as it:
                subs = sorted(Path(e.path) for e in it if e.is_dir(follow_symlinks=False))
        except OSError:
            continue
        for sub in subs:
            name = sub.name
            if name.startswith(".") or name in _SKIP or (sub / "CATKIN_IGNORE").exists():
                continue
            if (sub / "package.xml").is_file() and not (sub / "package.xml").is_symlink():
                found.append(sub)
            elif depth + 1 < _DEPTH:
                stack.append((sub, depth + 1))
    return sorted(found)


def _has_nodes(folder: Path) -> bool:
    """Does the package build a node (``add_executable`` outside a comment)?"""
    try:
        text = (folder / "CMakeLists.txt").read_text(encoding="utf-8", errors="replace")
    except OSError:
        return False
    return _ADD_EXECUTABLE.search(text) is not None


def find_package(path: str | os.PathLike[str]) -> Package:
    """The catkin package at ``path``: a folder with ``package.xml``, or the one package found
    in it as catkin would find it (a repository with the package in a subfolder, a catkin
    workspace ``src/<pkg>``, committed ``build/`` and ``devel/`` ignored: issue 31). Of
    several, the only one that builds a node; else a one-line usage error that lists the
    candidates and says how to choose (``--ros1 PATH/<pkg>``). usar's own ``fiducial_msgs``,
    as a workspace may hold it, is never the package."""
    root = Path(path)
    if not root.is_dir():
        raise UsageError(f"--ros1 {path}: no such folder (give a catkin package folder)")
    if (root / "package.xml").is_file():
        found = [root]
    else:
        found = [p for p in _package_dirs(root) if _name(p) != "fiducial_msgs"]
    if len(found) > 1:
        found = [p for p in found if _has_nodes(p)] or found
    if not found:
        raise NoPackage(f"--ros1 {path}: no package.xml found; give one catkin package folder")
    if len(found) > 1:
        rel = [p.relative_to(root).as_posix() for p in found]
        listed = ", ".join(rel[:6]) + (f" and {len(rel) - 6} more" if len(rel) > 6 else "")
        raise SeveralPackages(
            f"--ros1 {path}: {len(found)} catkin packages build nodes ({listed}); "
            f"choose one, e.g. --ros1 {root / rel[0]}"
        )
    name = _name(found[0])
    if name is None:
        raise UsageError(f"--ros1 {path}: {found[0] / 'package.xml'} has no <name>")
    return Package(found[0], name)


def _name(folder: Path) -> str | None:
    """The ``<name>`` in ``folder/package.xml`` (None when it has none or cannot be read)."""
    try:
        text = (folder / "package.xml").read_text(encoding="utf-8", errors="replace")
    except OSError:
        return None
    match = _NAME.search(text)
    return match.group(1) if match else None


def _files(pkg: Package) -> list[Entry]:
    """The package's files by :mod:`usar_replay.core.folder_walk`'s walk (the one ``usar
    batch`` checks a team's folder with: same rules, same caps), catkin's outputs left out:
    what is hashed is what is copied and built. A folder that breaks a rule is the package's
    ``build_failed``, its reason escaped text."""
    try:
        found = walk(pkg.path, skip_dirs=_SKIP, what=f"the folder of package {pkg.name}")
    except UnusableSubmission as err:
        raise MissionEnded("build_failed", f"package {pkg.name} cannot be built: {err}") from None
    return [e for e in found if e.link is None]


def package_sha256(pkg: Package) -> str:
    """sha256 over the package's files (relative path as bytes and bytes, in sorted order):
    the log says exactly which code ran (build outputs, ``.git``, hidden names left out:
    :func:`_files`)."""
    h = hashlib.sha256()
    try:
        for e in _files(pkg):
            h.update(len(e.rel).to_bytes(8, "little") + e.rel + e.size.to_bytes(8, "little"))
            stream(e, h.update)
    except UnusableSubmission as err:
        raise MissionEnded("build_failed", f"package {pkg.name} cannot be built: {err}") from None
    return h.hexdigest()


def _copy(pkg: Package, dest: Path) -> None:
    """The package's files (:func:`_files`) into ``dest``, each read from a checked
    descriptor and written to a new file (never through a link), with its mode bits."""
    try:
        for e in _files(pkg):
            target = dest / e.rel_path
            target.parent.mkdir(parents=True, exist_ok=True)
            flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW | os.O_CLOEXEC
            fd = os.open(target, flags, 0o600)
            with os.fdopen(fd, "wb") as out:
                mode = stream(e, out.write)
                os.fchmod(out.fileno(), (mode & 0o755) | 0o600)
    except UnusableSubmission as err:
        raise MissionEnded("build_failed", f"package {pkg.name} cannot be built: {err}") from None
    except OSError as err:  # a name too long, no space left: the package's verdict, said
        where = shown(err.filename) if isinstance(err.filename, str | bytes) else "a file"
        raise MissionEnded(
            "build_failed", f"package {pkg.name} could not be copied: {where}: {err.strerror}"
        ) from None


def catkin_env() -> dict[str, str]:
    """The environment catkin and roslaunch run in: Debian's tools first, no venv Python."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    env["PATH"] = "/usr/bin:/bin:" + env.get("PATH", "")
    env.setdefault("HOME", "/tmp")
    return env


def _toplevel(src: Path) -> None:
    """catkin_make's top-level CMakeLists.txt as a file of the workspace (catkin_make would make
    it a link into /usr, and a built workspace holds no link that leaves it)."""
    shutil.copyfile("/usr/share/catkin/cmake/toplevel.cmake", src / "CMakeLists.txt")


def sandboxed() -> bool:
    """Does a build run in the kernel sandbox here? (bubblewrap works, ``USAR_SANDBOX`` is not
    ``off``): only then can it be built at :mod:`~usar_replay.ros1.building.layout`'s fixed
    paths."""
    from usar_replay.sandbox import confinement

    return confinement.confined()


def warning_flags(folder: Path) -> tuple[str, ...]:
    """:data:`WARNING_FLAGS` for the package in ``folder`` (usar's copy of it), or () when one
    of its CMake files (``CMakeLists.txt``, ``*.cmake``) asks for ``-Werror``: with it, more
    warnings would make a build fail that builds on a course machine."""
    for path in sorted(folder.rglob("*")):
        if path.name != "CMakeLists.txt" and path.suffix != ".cmake":
            continue
        try:
            text = path.read_text(encoding="utf-8", errors="replace")
        except OSError:
            continue
        if _WERROR.search(text):
            return ()
    return WARNING_FLAGS


def _catkin_make(
    ws: Path,
    name: str,
    user: Path,
    underlays: tuple[Path, ...],
    limits: BuildLimits,
    jobs: int,
    at: str = "",
    flags: tuple[str, ...] = (),
) -> str:
    """Run catkin_make in ``ws`` (its ``src/`` filled) in the build's sandbox, where it appears
    at ``at`` and its underlays at :func:`~usar_replay.ros1.building.layout.underlay_at`
    (``at`` '': all
    at their host paths), with ``flags`` as the initial ``CMAKE_CXX_FLAGS``; raise
    :class:`BuildFailed` with the errors (paths as the student's) and a hint, or return its
    output as printed (paths as the build saw them)."""
    sandbox = sandboxed()
    if at and not sandbox:
        raise ValueError(f"a build at {at} needs the kernel sandbox")
    inside = Path(at) if at else ws
    seen = [layout.underlay_at(i) for i in range(len(underlays))] if at else underlays
    cmd = ["catkin_make", "-C", str(inside), "-DPYTHON_EXECUTABLE=/usr/bin/python3", f"-j{jobs}"]
    if flags:  # the cache's initial value: the package's CMakeLists.txt appends to it
        cmd.insert(4, "-DCMAKE_CXX_FLAGS=" + " ".join(flags))
    if underlays:  # as on a course machine: the underlay sourced, then catkin_make
        cmd = [
            "/bin/bash",
            "-c",
            'source "$0/devel/setup.bash" && exec "$@"',
            str(seen[-1]),
            *cmd,
        ]
    env = {"PATH": "/usr/bin:/bin", "HOME": "/tmp", "TMPDIR": "/tmp", "LANG": "C.UTF-8"}
    # catkin picks Debian's Python layout (dist-packages) by /etc/debian_version
    etc = [p for p in ("/etc/catkin", "/etc/ros", "/etc/debian_version") if Path(p).exists()]
    done = run_jailed(
        cmd,
        workspace=ws,
        ro_binds=[*etc] if at else [*etc, *map(str, underlays)],
        env=env if sandbox else catkin_env(),
        limits=limits,
        sandbox=sandbox,
        workspace_at=at,
        ro_mounts=layout.mounts(underlays) if at else (),
    )
    root = str(inside / "src" / name)
    output = buildmsg.student_paths(done.output, inside / "src" / name, user)
    if done.limit:
        raise BuildFailed(
            f"{buildmsg.errors(output)}\nthe build of {name} exceeded {done.limit}",
            done.output,
            root,
            flags,
        )
    if done.code != 0:
        said = buildmsg.hint(output, name)
        raise BuildFailed(
            f"catkin_make failed (exit {done.code}) for package {name}:\n"
            + buildmsg.errors(output)
            + (f"\n{said}" if said else "")
            + f"\ncatkin_make failed for package {name}",
            done.output,
            root,
            flags,
        )
    return done.output


def _seal(ws: Path, entry: Path, seconds: float, output: str, flags: tuple[str, ...]) -> None:
    """After the sandbox is gone: check ``ws`` (``build_failed`` when it holds a link out of it
    or a special file), freeze it, and write its manifest beside it, with catkin_make's
    output and the warning flags it was given (a cached build's output is the one it had)."""
    try:
        tree.check(ws)
    except tree.TreeRefused as err:
        raise MissionEnded("build_failed", str(err)) from err
    tree.freeze(ws)
    record = {
        "seconds": round(seconds, 1),
        "files": tree.manifest(ws),
        "output": output,
        "flags": list(flags),
    }
    tree.write_new(entry / _RECORD, json.dumps(record, sort_keys=True))


def build(
    pkg: Package,
    entry: Path,
    *,
    underlays: tuple[Path, ...] = (),
    jobs: int = 2,
    limits: BuildLimits | None = None,
    at: str = "",
    warnings: bool = False,
) -> Built:
    """Copy ``pkg`` into ``entry/ws/src`` (a new folder) and build it on ``underlays``; in the
    sandbox at ``at`` (:data:`usar_replay.ros1.building.layout.WORKSPACE`, the underlays at
    theirs) or,
    with ``at`` '', at its host path; ``warnings``: with :func:`warning_flags` (a team's
    package; usar's underlay is built without).

    ``entry`` is usar's: only ``entry/ws`` is writable by the build. A failure raises
    :class:`MissionEnded` ``build_failed`` with the compiler's errors."""
    entry.mkdir(mode=0o700)
    ws = entry / "ws"
    ws.mkdir()
    limits = limits or BuildLimits()
    # a size- and inode-limited tmpfs while the team's build runs, copied to disk after
    folder = BuildFolder(ws, limits.folder_mb if sandboxed() else 0)
    try:
        src = ws / "src"
        src.mkdir()
        _copy(pkg, src / pkg.name)
        _toplevel(src)
        flags = warning_flags(src / pkg.name) if warnings else ()
        start = time.perf_counter()  # for the build time shown to people only
        try:
            output = _catkin_make(ws, pkg.name, pkg.path, underlays, limits, jobs, at, flags)
        except MissionEnded as err:
            if folder.full():
                raise MissionEnded(
                    "build_failed", f"the build of {pkg.name} exceeded {folder.limit_words()}"
                ) from err
            raise
        if folder.full():  # a build that filled its folder and still said success
            raise MissionEnded(
                "build_failed", f"the build of {pkg.name} exceeded {folder.limit_words()}"
            )
        try:
            tree.check(ws)  # before copying: a link out of the workspace is never followed
        except tree.TreeRefused as err:
            raise MissionEnded("build_failed", str(err)) from err
        folder.keep()
    finally:
        folder.close()
    seconds = time.perf_counter() - start
    _seal(ws, entry, seconds, output, flags)
    return Built(ws, pkg, seconds, underlays=underlays, at=at, output=output, flags=flags)


def cache_root() -> Path:
    """Where built workspaces are kept: ``$XDG_CACHE_HOME/usar/ros1`` (``~/.cache/...``)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "usar" / "ros1"


def _private_root(root: Path) -> Path:
    """``root``, made if missing; refused unless it is a real folder of this user that nobody
    else may write (another user, or a sandbox, could otherwise plant a build)."""
    root.parent.mkdir(parents=True, exist_ok=True)
    with contextlib.suppress(FileExistsError):
        root.mkdir(mode=0o700)
    st = os.lstat(root)
    if not stat.S_ISDIR(st.st_mode) or st.st_uid != os.geteuid() or st.st_mode & 0o022:
        raise UsageError(
            f"{root}: the build cache must be a folder of this user that no one else may "
            "write; remove it, or set XDG_CACHE_HOME to a private folder"
        )
    return root


def remove_tree(path: Path) -> None:
    """Remove a (frozen) build folder: write bits back on its real folders first, then the
    whole tree. Never through a link, never a chmod of one (a build may leave links to
    folders, in or out of its workspace: issue 33); a folder is opened ``O_NOFOLLOW`` and
    changed through its descriptor."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        return
    if not stat.S_ISDIR(st.st_mode):
        path.unlink()
        return
    for dirpath, dirnames, _ in os.walk(path):  # os.walk never descends into a link
        for folder in (dirpath, *(os.path.join(dirpath, d) for d in dirnames)):
            with contextlib.suppress(OSError):
                fd = os.open(folder, os.O_RDONLY | os.O_DIRECTORY | os.O_NOFOLLOW | os.O_CLOEXEC)
                try:
                    os.fchmod(fd, 0o700)
                finally:
                    os.close(fd)
    shutil.rmtree(path, ignore_errors=True)


def _usar_key(h: hashlib._Hash, fixed: bool) -> None:
    from usar_replay import __version__

    h.update(standins.sha256().encode())  # fiducial_msgs and the stand-ins
    h.update(__version__.encode())
    h.update(str(shutil.which("g++")).encode())
    h.update((layout.VERSION if fixed else layout.HOST).encode())


def _reuse(entry: Path, pkg: Package, underlays: tuple[Path, ...]) -> Built | None:
    """The build at ``entry`` when it is exactly as it was built (its manifest), else None."""
    try:
        fd = os.open(entry / _RECORD, os.O_RDONLY | os.O_NOFOLLOW | os.O_CLOEXEC)
        with os.fdopen(fd, "r", encoding="utf-8") as f:
            record = json.load(f)
        files = {str(k): str(v) for k, v in record["files"].items()}
        output = str(record["output"])
        flags = tuple(str(f) for f in record["flags"])
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return None  # an entry without its output: rebuilt, so a hit says what a build says
    if tree.verify(entry / "ws", files):
        return None
    return Built(entry / "ws", pkg, 0.0, True, underlays, output=output, flags=flags)


def _cached(root: Path, key: str, pkg: Package, make: Callable[[Path], Built]) -> Built:
    """The verified build ``root/key``, or a new one made by ``make(entry)`` under a lock."""
    entry = root / key
    lock_fd = os.open(
        root / f"{key}.lock", os.O_RDWR | os.O_CREAT | os.O_NOFOLLOW | os.O_CLOEXEC, 0o600
    )
    try:
        fcntl.flock(lock_fd, fcntl.LOCK_EX)
        found = _reuse(entry, pkg, ()) if entry.is_dir() else None
        if found is not None:
            return found
        remove_tree(entry)  # a cut-off build, or one that changed since: never trusted
        try:
            return make(entry)
        except BaseException:
            remove_tree(entry)
            raise
    finally:
        os.close(lock_fd)


def underlay(
    root: Path | None = None, limits: BuildLimits | None = None, *, fixed: bool = False
) -> Path:
    """usar's ``fiducial_msgs``, ``usar_pacing`` (the preloaded shim, :mod:`.shim`) and the
    stand-ins (:mod:`.standins`) built in a workspace of their
    own (cached and verified like any build: they are usar's own bytes, so every run may share
    them, and no sandbox can write them); ``fixed``: at
    :data:`usar_replay.ros1.building.layout.UNDERLAY` in the sandbox (when there is one)."""
    root = _private_root(root or cache_root())
    fixed = fixed and sandboxed()
    h = hashlib.sha256(b"underlay")
    _usar_key(h, fixed)
    key = f"underlay-{h.hexdigest()[:20]}"
    at = layout.UNDERLAY if fixed else ""

    def make(entry: Path) -> Built:
        with tempfile.TemporaryDirectory(prefix="usar-underlay-") as tmp:
            source = Package(Path(tmp) / standins.UNDERLAY, standins.UNDERLAY)
            standins.write(source.path)
            return build(source, entry, limits=limits, at=at)

    where = Package(root / key, standins.UNDERLAY)
    return _cached(root, key, where, make).workspace


def cached_build(
    pkg: Package,
    root: Path | None = None,
    limits: BuildLimits | None = None,
    *,
    fixed: bool = False,
) -> Built:
    """:func:`build` once per package content: a workspace built before from the same files
    (same fiducial_msgs, same usar, same compiler) is reused when it is exactly as its manifest
    says, read only. Why: catkin_make costs ~40 s of CPU, and a class's runs (or a test's
    variants of one package) build the same files. Two teams share a build only when their
    packages are the same bytes: the build ran those bytes alone, and nothing but usar can
    write the cache. Built in place (catkin writes absolute paths into ``devel/``), under a
    lock; a failed build is not kept. ``fixed``: built at the sandbox's fixed paths
    (:mod:`usar_replay.ros1.building.layout`) when the build has a sandbox, for a run that has
    one."""
    root = _private_root(root or cache_root())
    fixed = fixed and sandboxed()
    under = () if pkg.name == "fiducial_msgs" else (underlay(root, limits, fixed=fixed),)
    h = hashlib.sha256()
    h.update(package_sha256(pkg).encode())
    _usar_key(h, fixed)
    h.update(" ".join(WARNING_FLAGS).encode())  # its output is kept: the flags it was built with
    key = f"{pkg.name}-{h.hexdigest()[:20]}"
    at = layout.WORKSPACE if fixed else ""
    made = _cached(
        root,
        key,
        pkg,
        lambda entry: build(pkg, entry, underlays=under, limits=limits, at=at, warnings=True),
    )
    return Built(
        made.workspace, pkg, made.seconds, made.cached, under, at, made.output, made.flags
    )


def private_build(
    pkg: Package, limits: BuildLimits | None = None, *, fixed: bool = False
) -> tuple[Built, Path]:
    """:func:`build` in a fresh folder of its own (no cache; the underlay still is): the
    built workspace and the folder to remove with :func:`remove_tree` when done (``fixed``
    as for :func:`cached_build`)."""
    fixed = fixed and sandboxed()
    under = () if pkg.name == "fiducial_msgs" else (underlay(None, limits, fixed=fixed),)
    at = layout.WORKSPACE if fixed else ""
    holder = Path(tempfile.mkdtemp(prefix="usar-ros1-build-"))
    try:
        built = build(pkg, holder / "entry", underlays=under, limits=limits, at=at, warnings=True)
        return built, holder
    except BaseException:
        remove_tree(holder)
        raise
