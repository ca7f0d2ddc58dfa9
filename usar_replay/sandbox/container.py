"""Is usar in a container, and what would its sandbox and cgroups need of the container's run?

Why: Docker's and Kubernetes' defaults (Gradescope, GitHub Actions' ``container:`` jobs, most
course servers) refuse what bubblewrap and the cgroups need: the default seccomp profile
refuses the namespace-creating calls to a process without ``CAP_SYS_ADMIN``, AppArmor's
``docker-default`` refuses ``mount``, the masked ``/proc`` paths keep the kernel from mounting
a fresh ``/proc``, and the cgroup file systems are mounted read-only unless the container is
privileged. Each has a run flag that lifts it; ``usar doctor`` names those the machine lacks and
what each costs, instead of a way around the sandbox.

Measured with Docker 20.10.24 (Debian's ``docker.io``) on a cgroup v1 (hybrid) host without
systemd or AppArmor: the defaults give neither the sandbox nor the cgroups (a Debian 12 VM with
Docker 20.10 refused the sandbox too); the three ``--security-opt`` flags give the sandbox
(there too) and leave the cgroups read-only (``--cgroupns=private`` or ``--cap-add SYS_ADMIN``
beside them change nothing); ``--privileged`` gives both, with the host's cgroup namespace (v1's
default) or ``--cgroupns=private``. Binding the host's ``-v /sys/fs/cgroup:/sys/fs/cgroup:rw``
also gives the cgroups on v1, but with every cgroup of the host writable to the container's
root: not suggested. Measured on a stock Debian 12 VM (cgroup v2, systemd's cgroup driver,
Docker 20.10.24): the defaults give neither; the flags ``usar doctor`` names there (the three
``--security-opt`` and ``--privileged``), or ``--privileged`` alone, give every line: Docker's
default on v2 is a private cgroup namespace, whose root usar empties into a leaf before it
enables the controllers (:mod:`.cgroup_v2`). ``--cgroupns=private`` is named only where the
container shows the host's cgroup paths (:func:`needs`; not measured: Docker's
``--cgroupns=host`` on v2). Kubernetes was not measured.

The signs are read from the files the kernel and the runtimes leave (:func:`read`) and judged
by pure functions of their text (:func:`signs_from`), so the judgement is tested on each shape.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from usar_replay.sandbox.mountinfo import Mount
from usar_replay.sandbox.mountinfo import parse as parse_mounts
from usar_replay.sandbox.mountinfo import read as read_mountinfo

__all__ = [
    "APPARMOR",
    "CGROUPS",
    "CGROUPS_PRIVATE",
    "SECCOMP",
    "SYSTEMPATHS",
    "Need",
    "Signs",
    "kind",
    "needs",
    "read",
    "signs_from",
]


@dataclass(frozen=True, slots=True)
class Signs:
    """What the files say about the container usar runs in (if any)."""

    dockerenv: bool = False
    """``/.dockerenv`` exists (Docker)."""
    containerenv: bool = False
    """``/run/.containerenv`` exists (Podman)."""
    container_env: str = ""
    """PID 1's ``container=`` variable (Podman, systemd-nspawn, LXC set it)."""
    kubernetes: bool = False
    """``KUBERNETES_SERVICE_HOST`` is set or a service account is mounted."""
    runtime_cgroup: bool = False
    """This process's cgroup path names a runtime (docker, containerd, kubepods, libpod)."""
    seccomp: int = 0
    """``Seccomp:`` of ``/proc/self/status`` (2: a filter, as Docker's default profile)."""
    apparmor: str = ""
    """This process's AppArmor label (``docker-default (enforce)``), '' without AppArmor."""
    proc_masked: bool = False
    """Parts of ``/proc`` are mounted over (Docker's masked and read-only paths)."""
    cgroup_read_only: bool = False
    """A cgroup file system at or below ``/sys/fs/cgroup`` is mounted read-only (v2's one
    mount, or any of v1's per-controller ones; a read-only tmpfs holding them is no sign)."""
    cgroupns_private: bool = False
    """Every line of ``/proc/self/cgroup`` is at ``/``: the container has a cgroup namespace of
    its own (the host's shows ``/docker/<id>`` or the like)."""


def _cgroup_read_only(mounts: list[Mount]) -> bool:
    return any(
        m.fstype in ("cgroup", "cgroup2")
        and (m.point == "/sys/fs/cgroup" or m.point.startswith("/sys/fs/cgroup/"))
        and "ro" in m.options
        for m in mounts
    )


def _private_cgroupns(proc_cgroup: str) -> bool:
    paths = [line.split(":", 2)[2] for line in proc_cgroup.splitlines() if line.count(":") >= 2]
    return bool(paths) and all(p == "/" for p in paths)


def signs_from(
    *,
    files: Mapping[str, bool],
    pid1_environ: bytes = b"",
    environ: Mapping[str, str] | None = None,
    proc_cgroup: str = "",
    status: str = "",
    apparmor: str = "",
    mountinfo: str = "",
) -> Signs:
    """The signs, from the texts of the files they are read from (``files``: which of
    ``/.dockerenv``, ``/run/.containerenv``, the Kubernetes service account exist)."""
    env = environ or {}
    pid1 = dict(
        item.split(b"=", 1) for item in pid1_environ.split(b"\0") if b"=" in item
    )  # fmt: skip
    seccomp = 0
    for line in status.splitlines():
        if line.startswith("Seccomp:"):
            seccomp = int(line.split()[1])
    mounts = parse_mounts(mountinfo)
    label = apparmor.strip().strip("\0")
    return Signs(
        dockerenv=files.get("/.dockerenv", False),
        containerenv=files.get("/run/.containerenv", False),
        container_env=pid1.get(b"container", b"").decode(errors="replace"),
        kubernetes="KUBERNETES_SERVICE_HOST" in env
        or b"KUBERNETES_SERVICE_HOST" in pid1
        or files.get("/var/run/secrets/kubernetes.io", False),
        runtime_cgroup=any(
            word in proc_cgroup for word in ("docker", "containerd", "kubepods", "libpod")
        ),
        seccomp=seccomp,
        apparmor="" if label in ("", "unconfined") else label,
        proc_masked=any(m.point.startswith("/proc/") for m in mounts),
        cgroup_read_only=_cgroup_read_only(mounts),
        cgroupns_private=_private_cgroupns(proc_cgroup),
    )


def _text(path: str) -> str:
    try:
        return Path(path).read_text(errors="replace")
    except OSError:
        return ""


def read() -> Signs:
    """The signs of this process's machine."""
    try:
        pid1 = Path("/proc/1/environ").read_bytes()
    except OSError:
        pid1 = b""  # another user's PID 1: not readable, and no sign either way
    paths = ("/.dockerenv", "/run/.containerenv", "/var/run/secrets/kubernetes.io")
    return signs_from(
        files={p: os.path.exists(p) for p in paths},
        pid1_environ=pid1,
        environ=os.environ,
        proc_cgroup=_text("/proc/self/cgroup"),
        status=_text("/proc/self/status"),
        apparmor=_text("/proc/self/attr/current"),
        mountinfo=read_mountinfo(),
    )


def kind(signs: Signs) -> str:
    """Which container this is (``docker``, ``podman``, ``kubernetes``, ``lxc``...), '' where
    none is recognised."""
    if signs.kubernetes:
        return "kubernetes"
    if signs.dockerenv:
        return "docker"
    if signs.containerenv:
        return "podman"
    if signs.container_env:
        return signs.container_env
    return "container" if signs.runtime_cgroup else ""


@dataclass(frozen=True, slots=True)
class Need:
    """One setting of the container's run that usar lacks, and what lacking it costs."""

    docker: str
    """The ``docker run`` flag (Podman's are the same)."""
    kubernetes: str
    """The pod's ``securityContext`` setting."""
    cost: str
    """What a run lacks without it."""


SECCOMP = Need(
    "--security-opt seccomp=unconfined",
    "seccompProfile: {type: Unconfined}",
    "no sandbox: namespaces refused",
)
APPARMOR = Need(
    "--security-opt apparmor=unconfined",
    "appArmorProfile: {type: Unconfined}",
    "no sandbox: mounts refused",
)
SYSTEMPATHS = Need(
    "--security-opt systempaths=unconfined",
    "procMount: Unmasked",
    "no sandbox: /proc masked",
)
CGROUPS = Need(
    "--privileged",
    "privileged: true",
    "no per-run memory, pids, CPU set",
)
"""What gives a container its cgroups (measured on v1: nothing short of it, module doc)."""
CGROUPS_PRIVATE = Need(
    "--privileged --cgroupns=private",
    "privileged: true",
    "no per-run memory, pids, CPU set",
)
"""The same where cgroup v2 shows the host's cgroup paths: privileged in the host's namespace,
usar's cgroups would be made at the host's root rather than below the container's own (not
measured: Docker's default on v2, measured, is a private namespace and needs no flag for it)."""


def needs(
    signs: Signs, *, sandbox_ok: bool, cgroups_ok: bool, cgroup_version: int = 1
) -> list[Need]:
    """The settings this container's run lacks for the sandbox (where bubblewrap fails here)
    and for the runs' cgroups (where they are not all usar's), each named where its sign is
    seen; all three of the sandbox's where bubblewrap fails without one (a runtime's own
    profile). ``--cgroupns=private`` only on v2 outside a namespace of the container's own: v1
    needs none (measured), and a v2 container has its own by default."""
    out: list[Need] = []
    if not sandbox_ok:
        seen = [
            n
            for n, sign in (
                (SECCOMP, signs.seccomp == 2),
                (APPARMOR, bool(signs.apparmor)),
                (SYSTEMPATHS, signs.proc_masked),
            )
            if sign
        ]
        out += seen or [SECCOMP, APPARMOR, SYSTEMPATHS]
    if not cgroups_ok:
        host_paths = cgroup_version == 2 and not signs.cgroupns_private
        out.append(CGROUPS_PRIVATE if host_paths else CGROUPS)
    return out
