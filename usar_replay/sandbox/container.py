"""Is usar in a container, and what would its sandbox and cgroups need of the container's run?

Why: Docker's and Kubernetes' defaults (Gradescope, GitHub Actions' ``container:`` jobs, most
course servers) refuse what bubblewrap and the cgroups need: the default seccomp profile
refuses the namespace-creating calls to a process without ``CAP_SYS_ADMIN``, AppArmor's
``docker-default`` refuses ``mount``, the masked ``/proc`` paths keep the kernel from mounting
a fresh ``/proc``, and ``/sys/fs/cgroup`` is read-only unless the container is privileged. Each
has a run flag that lifts it; ``usar doctor`` names those the machine lacks and what each
costs, instead of a way around the sandbox. (Which of the three ``--security-opt`` flags alone
suffices depends on the kernel and runtime: measured in a Debian 12 VM with Docker 20.10, the
three together or ``--privileged`` work, the default does not.)

The signs are read from the files the kernel and the runtimes leave (:func:`read`) and judged
by pure functions of their text (:func:`signs_from`), so the judgement is tested on each shape.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

__all__ = ["Need", "Signs", "kind", "needs", "read", "signs_from"]


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
    """``/sys/fs/cgroup`` is mounted read-only."""


def _mount_points(mountinfo: str) -> list[tuple[str, list[str]]]:
    """(mount point, mount options) of each ``/proc/self/mountinfo`` line."""
    out = []
    for line in mountinfo.splitlines():
        fields = line.split()
        if len(fields) > 5:
            out.append((fields[4].replace("\\040", " "), fields[5].split(",")))
    return out


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
    points = _mount_points(mountinfo)
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
        proc_masked=any(p.startswith("/proc/") for p, _ in points),
        cgroup_read_only=any(p == "/sys/fs/cgroup" and "ro" in o for p, o in points),
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
        mountinfo=_text("/proc/self/mountinfo"),
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
    "--cgroupns=private, cgroup fs rw",
    "privileged: true",
    "no memory, process, CPU bound a run",
)


def needs(signs: Signs, *, sandbox_ok: bool, cgroups_ok: bool) -> list[Need]:
    """The settings this container's run lacks for the sandbox (where bubblewrap fails here)
    and for the runs' cgroups (where they are not all usar's), each named where its sign is
    seen; all three of the sandbox's where bubblewrap fails without one (a runtime's own
    profile)."""
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
        out.append(CGROUPS)
    return out
