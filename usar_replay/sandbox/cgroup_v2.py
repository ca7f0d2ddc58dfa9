"""cgroup v2 (one unified hierarchy), the backend :mod:`.cgroups` picks where ``/sys/fs/cgroup``
is ``cgroup2fs``: a stock Debian 12, Ubuntu 22.04+, Fedora, GitHub's runners, Docker on those.

Why it is not v1 with other file names: in v2 a cgroup that holds processes cannot hand a
controller to its children (the "no internal processes" rule), and a process may write only
where its cgroup was delegated to it. So usar first obtains a subtree of its own (its
*base*), in this order:

1. its own cgroup is ``<base>/usar-self``: a usar process above it did the rest (a batch's
   run processes, started by the driver);
2. its own cgroup was delegated to it (systemd's ``Delegate=yes``, marked by the
   ``trusted.delegate``/``user.delegate`` attribute or owned by the user; a container's own
   cgroup namespace, as root): that cgroup;
3. systemd runs the machine: a transient scope ``usar-PID.scope`` with ``Delegate=yes`` that
   this process moves into (``StartTransientUnit`` through ``busctl``; the system manager as
   root, the user's own manager otherwise);
4. root without either: ``/sys/fs/cgroup/usar``, with the controllers enabled top-down.

In 1-3 usar then moves every process of the base into a leaf, ``<base>/usar-self``, and only
then writes ``+cpuset +memory +pids`` to the base's ``cgroup.subtree_control`` (as isolate,
nsjail and systemd's own delegation rules do). Each run is a child of the base with its limits:
``pids.max``, ``memory.max`` with ``memory.swap.max`` 0 and ``memory.oom.group`` 1 (socket
buffers are charged to the same memory: v1's separate TCP cap has no v2 counterpart) and its
CPUs (``cpuset.cpus``). It is removed with ``cgroup.kill`` and ``rmdir``.

A user's own systemd manager delegates only what ``user@.service`` is given (a stock one:
``memory pids``, not ``cpuset``): :data:`DROP_IN` is what adds it.
"""

from __future__ import annotations

import contextlib
import functools
import os
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

from usar_replay.sandbox import cgroup_v1
from usar_replay.sandbox import mountinfo as mountinfo_

__all__ = [
    "DROP_IN",
    "DROP_IN_PATH",
    "NEED",
    "SELF",
    "Subtree",
    "make_run",
    "remove",
    "scope_argv",
    "subtree",
    "unified_path",
]

MOUNT = "/sys/fs/cgroup"
NEED = ("cpuset", "memory", "pids")
"""The controllers a run's cgroup needs: its CPUs, its memory, its process count."""
SELF = "usar-self"
"""The leaf usar's own processes move into, below the base (the no-internal-process rule)."""
OWN = "usar"
"""The base root makes below the root where nothing delegates one (step 4)."""
DROP_IN_PATH = "/etc/systemd/system/user@.service.d/delegate.conf"
DROP_IN = "[Service]\nDelegate=cpu cpuset io memory pids\n"
"""What makes a user's systemd manager delegate ``cpuset`` too (then ``systemctl
daemon-reload`` and a new login)."""


@dataclass(frozen=True, slots=True)
class Subtree:
    """The cgroup v2 subtree usar makes its runs' cgroups in."""

    path: str | None
    """The base folder (None: none could be had)."""
    how: str
    """How it was had (``usar-12.scope (systemd, Delegate=yes)``: a transient scope)."""
    enabled: tuple[str, ...] = ()
    """Which of :data:`NEED` its children get."""
    why: str = ""
    """Why not all of :data:`NEED` (empty where all)."""
    user_manager: bool = False
    """Had from a user's own systemd manager (what :data:`DROP_IN` changes)."""


def unified_path(proc_cgroup: str) -> str | None:
    """The v2 path of a process from its ``/proc/PID/cgroup`` text (``0::/a/b`` -> ``/a/b``)."""
    for line in proc_cgroup.splitlines():
        if line.startswith("0::"):
            return line[3:].strip() or "/"
    return None


def parse_controllers(text: str) -> tuple[str, ...]:
    """``cgroup.controllers`` or ``cgroup.subtree_control`` text -> the names."""
    return tuple(text.split())


def scope_argv(unit: str, pid: int, user: bool) -> list[str]:
    """``busctl`` asking systemd (the user's own manager with ``user``) for the transient scope
    ``unit`` holding ``pid``, its controllers delegated, collected once empty."""
    return [
        "busctl", *(["--user"] if user else []), "call", "org.freedesktop.systemd1",
        "/org/freedesktop/systemd1", "org.freedesktop.systemd1.Manager", "StartTransientUnit",
        "ssa(sv)a(sa(sv))", unit, "fail", "4",
        "PIDs", "au", "1", str(pid),
        "Delegate", "b", "true",
        "CollectMode", "s", "inactive-or-failed",
        "Description", "s", "usar: the cgroups of its runs",
        "0",
    ]  # fmt: skip


def _read(path: str) -> str:
    try:
        return Path(path).read_text()
    except OSError:
        return ""


def _mount_root(mountinfo: str) -> str:
    """The root within the hierarchy of the ``cgroup2`` mount at :data:`MOUNT` (``/`` where
    mountinfo names none)."""
    for m in mountinfo_.parse(mountinfo):
        if m.fstype == "cgroup2" and m.point == MOUNT:
            return m.root
    return "/"


def _own(proc_cgroup: str | None = None, mountinfo: str | None = None) -> str | None:
    """This process's cgroup folder (``proc_cgroup``, ``mountinfo``: the texts of
    ``/proc/self/cgroup`` and ``/proc/self/mountinfo``, read when not given).

    Why the mount's root, as on v1 (:func:`.cgroup_v1.controller_root`): a container that
    shares the host's cgroup namespace (``--cgroupns=host``) reads ``0::/docker/<id>`` while
    its ``/sys/fs/cgroup`` already shows that folder; the folder is the path less the mount's
    root, and a cgroup outside the mounted subtree has none here."""
    path = unified_path(_read("/proc/self/cgroup") if proc_cgroup is None else proc_cgroup)
    if path is None:
        return None
    if mountinfo is None:
        mountinfo = mountinfo_.read()
    root = _mount_root(mountinfo).rstrip("/")
    if path != root and not path.startswith(root + "/"):
        return None
    return os.path.normpath(MOUNT + "/" + path[len(root) :].lstrip("/"))


def _writable(folder: str) -> bool:
    return all(
        os.access(os.path.join(folder, name), os.W_OK)
        for name in ("cgroup.procs", "cgroup.subtree_control")
    ) and os.access(folder, os.W_OK)


def _delegated(folder: str) -> bool:
    """Whether ``folder`` is usar's to divide: systemd marks a delegated cgroup, a user's is
    owned by the user, and root's own cgroup namespace shows its root at the mount."""
    if not _writable(folder):
        return False
    if folder == MOUNT:
        return True  # the root of this cgroup namespace (a container's own, or the machine's)
    for name in ("trusted.delegate", "user.delegate"):
        with contextlib.suppress(OSError):
            if os.getxattr(folder, name).strip(b"\0") == b"1":
                return True
    if os.geteuid() != 0:
        with contextlib.suppress(OSError):
            return os.stat(os.path.join(folder, "cgroup.subtree_control")).st_uid == os.geteuid()
    return False


def _move_all(folder: str, leaf: str) -> None:
    """Every process of ``folder`` into ``leaf`` (new ones may appear while moving)."""
    for _ in range(50):
        pids = _read(os.path.join(folder, "cgroup.procs")).split()
        if not pids:
            return
        for pid in pids:
            with contextlib.suppress(OSError):  # gone meanwhile, or a kernel thread
                Path(leaf, "cgroup.procs").write_text(pid)


def _machine_root(folder: str) -> bool:
    """Whether ``folder`` is the machine's root cgroup: the kernel gives every other cgroup a
    ``cgroup.type`` file, the root none (a container's namespace root has one: it is not)."""
    return not os.path.exists(os.path.join(folder, "cgroup.type"))


def _enable(folder: str) -> tuple[tuple[str, ...], str]:
    """Enable each of :data:`NEED` that ``folder`` has for its children: (enabled, why not the
    others).

    Why nothing at all is written where ``folder`` holds processes and is not the machine's
    root: the kernel would take ``+cpuset`` and ``+pids`` there (threaded controllers may sit
    beside processes) and so make ``folder`` a thread root, after which ``+memory`` fails with
    EOPNOTSUPP and no process can move into a child (measured in a privileged Docker container
    on Debian 12: its processes stayed, memory was refused). Its processes move out first
    (:func:`_take`)."""
    have = parse_controllers(_read(os.path.join(folder, "cgroup.controllers")))
    done = parse_controllers(_read(os.path.join(folder, "cgroup.subtree_control")))
    enabled: list[str] = []
    said: list[str] = []
    missing = [n for n in NEED if n not in done]
    held = _read(os.path.join(folder, "cgroup.procs")).split()
    if missing and held and not _machine_root(folder):
        why = f"{folder} holds processes (v2 hands controllers on only from a cgroup without any)"
        return tuple(n for n in NEED if n in done), why
    for name in NEED:
        if name in done:
            enabled.append(name)
        elif name not in have:
            said.append(f"{name} not delegated to {folder}")
        else:
            try:
                Path(folder, "cgroup.subtree_control").write_text(f"+{name}")
                enabled.append(name)
            except OSError as err:
                said.append(f"+{name} refused in {folder} ({err.strerror})")
    return tuple(enabled), "; ".join(said)


def _take(folder: str, how: str, user_manager: bool = False) -> Subtree:
    """``folder`` as the base: its processes into :data:`SELF`, then the controllers on."""
    done = parse_controllers(_read(os.path.join(folder, "cgroup.subtree_control")))
    if not all(n in done for n in NEED):
        leaf = os.path.join(folder, SELF)
        try:
            with contextlib.suppress(FileExistsError):
                os.mkdir(leaf)
        except OSError as err:
            return Subtree(None, how, why=f"cannot make {leaf} ({err.strerror})")
        _move_all(folder, leaf)
    enabled, why = _enable(folder)
    return Subtree(folder, how, enabled, why, user_manager)


def _top_down() -> Subtree:
    """Root without a delegation: ``/sys/fs/cgroup/usar`` with the controllers enabled from the
    root down (the root cgroup may hold processes and still hand controllers on)."""
    _, why = _enable(MOUNT)
    base = os.path.join(MOUNT, OWN)
    try:
        with contextlib.suppress(FileExistsError):
            os.mkdir(base)
    except OSError as err:
        return Subtree(None, "", why=f"cannot make {base} ({err.strerror})")
    enabled, why2 = _enable(base)
    return Subtree(base, f"{base} (root, enabled from the root down)", enabled, why2 or why)


def _systemd() -> bool:
    return os.path.isdir("/run/systemd/system")


def _new_scope() -> tuple[str | None, str]:
    """A transient scope of systemd's holding this process: (its folder, '') or (None, why)."""
    user = os.geteuid() != 0
    pid = os.getpid()
    unit = f"usar-{pid}.scope"
    try:
        done = subprocess.run(
            scope_argv(unit, pid, user), capture_output=True, text=True, timeout=30, check=False
        )
    except (OSError, subprocess.TimeoutExpired) as err:
        return None, f"busctl could not be run ({err})"
    if done.returncode != 0:
        said = (done.stderr.strip().splitlines() or [f"exit {done.returncode}"])[-1]
        manager = "the user's systemd manager" if user else "systemd"
        return None, f"{manager} made no delegated scope ({said})"
    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline:  # the job moves this process once systemd runs it
        own = _own()
        if own is not None and os.path.basename(own) == unit:
            return own, ""
        time.sleep(0.01)
    return None, f"systemd did not move usar into {unit} within 10 s"


Step = str
"""One way to a base: ``parent`` (the usar process above's), ``own`` (this process's delegated
cgroup), ``root`` (the machine's root cgroup, from the root down), ``scope`` (a transient systemd
scope), ``top-down`` (root's ``/sys/fs/cgroup/usar``)."""


def plan(
    *,
    in_leaf: bool,
    delegated: bool,
    at_mount: bool,
    root: bool,
    systemd: bool,
    machine_root: bool,
) -> list[Step]:
    """The ways to a base to try, in order, for a process whose cgroup is ``usar-self`` below
    a base already made (``in_leaf``), is delegated to it (``delegated``), is the mount's root
    (``at_mount``: the machine's root or a container's cgroup namespace; ``machine_root``:
    the former), as root or not, with systemd running or not. The first that gives every
    controller wins; else the last that gives any."""
    if in_leaf:
        return ["parent"]
    if delegated:
        # at the mount as root: the machine's own root cgroup may hand controllers down while
        # it holds processes; a container namespace's root may not, so its processes move
        return ["root", "own"] if at_mount and root and machine_root else ["own"]
    return [*(["scope"] if systemd else []), *(["top-down"] if root else [])]


def _step(step: Step, own: str) -> Subtree:
    user = os.geteuid() != 0
    if step == "parent":
        parent = os.path.dirname(own)
        on, why = _enable(parent)  # the same answer the usar process above had
        return Subtree(parent, f"{parent} (a usar process's above)", on, why, user)
    if step == "own":
        return _take(own, f"{own} (delegated to usar)", user_manager=user)
    if step == "scope":
        scope, said = _new_scope()
        if scope is None:
            return Subtree(None, "", why=said)
        return _take(scope, f"{os.path.basename(scope)} (systemd, Delegate=yes)", user)
    if step == "root":
        enabled, why = _enable(MOUNT)
        if len(enabled) < len(NEED):
            return Subtree(None, "", why=why)
    return _top_down()


@functools.cache
def subtree() -> Subtree:
    """The base usar's runs' cgroups are made in (obtained once per process: :func:`plan`,
    and the module doc). A forked child inherits the answer, which holds for it too: it starts
    in the same cgroup."""
    if not os.path.exists(os.path.join(MOUNT, "cgroup.controllers")):
        return Subtree(None, "", why=f"{MOUNT} is not cgroup v2")
    own = _own()
    if own is None:
        return Subtree(None, "", why="this process has no cgroup v2 path")
    parent = os.path.dirname(own)
    done = parse_controllers(_read(os.path.join(parent, "cgroup.subtree_control")))
    steps = plan(
        in_leaf=os.path.basename(own) == SELF
        and _writable(parent)
        and any(n in done for n in NEED),
        delegated=_delegated(own),
        at_mount=own == MOUNT,
        machine_root=_machine_root(MOUNT),
        root=os.geteuid() == 0,
        systemd=_systemd(),
    )
    best = Subtree(None, "", why=f"{own} is not delegated to usar")
    for step in steps:
        got = _step(step, own)
        if got.path is not None and len(got.enabled) == len(NEED):
            return got
        if got.path is not None and (best.path is None or len(got.enabled) > len(best.enabled)):
            best = got
        elif best.path is None and got.why:
            best = Subtree(None, "", why=got.why)
    return best


def enabled() -> tuple[str, ...]:
    """Which of :data:`NEED` a run's cgroup gets here."""
    return subtree().enabled


def make_run(
    name: str, *, processes: int = 0, memory_mb: int = 0, cpus: tuple[int, ...] = ()
) -> str | None:
    """A run's cgroup ``name`` below the base, with its limits (0 or (): none of that kind);
    None where there is no base or the kernel refuses one of them (never a run with less
    than was asked for a controller the base has)."""
    got = subtree()
    if got.path is None:
        return None
    path = os.path.join(got.path, name)
    try:
        os.mkdir(path)
    except OSError:
        return None
    try:
        if cpus and "cpuset" in got.enabled:
            Path(path, "cpuset.cpus").write_text(",".join(map(str, cpus)))
        set_limits(path, processes=processes, memory_mb=memory_mb)
    except OSError:
        remove(path)
        return None
    return path


def set_limits(path: str, *, processes: int = 0, memory_mb: int = 0) -> None:
    """Write a run's process and memory limits in its cgroup (for the controllers on)."""
    got = subtree().enabled
    if processes > 0 and "pids" in got:
        Path(path, "pids.max").write_text(str(processes))
    if "memory" in got:
        Path(path, "memory.oom.group").write_text("1")  # an OOM kill ends the run as a whole
        if memory_mb > 0:
            Path(path, "memory.max").write_text(str(memory_mb * 1024 * 1024))
            with contextlib.suppress(OSError):  # no swap controller: no swap to limit
                Path(path, "memory.swap.max").write_text("0")


def cpu_root() -> tuple[str, str] | None:
    """(CPU list, memory nodes) the base has for its children's CPU sets, as the kernel writes
    them, or None where a run gets no CPU set here."""
    got = subtree()
    if got.path is None or "cpuset" not in got.enabled:
        return None
    try:
        cpus = Path(got.path, "cpuset.cpus.effective").read_text()
        mems = Path(got.path, "cpuset.mems.effective").read_text().strip()
    except OSError:
        return None
    return cpus, mems


def remove(path: str) -> None:
    """Remove a run's cgroup: ``cgroup.kill`` ends every process in it and below (Linux 5.14+;
    SIGKILL to each member before that), then ``rmdir``, children first."""
    with contextlib.suppress(OSError):
        for name in os.listdir(path):
            child = os.path.join(path, name)
            if os.path.isdir(child):
                remove(child)
    cgroup_v1.rmdir_killing(path, _kill)


def _kill(path: str) -> None:
    """End every process of a cgroup: ``cgroup.kill`` where the kernel has it, else SIGKILL to
    each member."""
    try:
        Path(path, "cgroup.kill").write_text("1")
    except OSError:
        cgroup_v1.kill_members(path)
