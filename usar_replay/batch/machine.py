"""What this machine gives a run, and what that means for grades (``usar doctor``, issue 44).

Why: usar's isolation is made of the kernel's parts (bubblewrap's namespaces, cgroups, CPU
sets, real-time priority), and a machine may lack some of them: a container without cgroup
delegation, a laptop without root, a cluster node without ROS 1. A run goes on with what there
is, but what is missing changes what a grade can be trusted for (a neighbour on the same CPUs
can change a ROS 1 run's log). This module asks the same functions the runs use, so what it
says is what a run gets; :func:`warning` is the one line ``usar batch`` prints at its start
where isolation is partial.
"""

from __future__ import annotations

import os
import resource
from dataclasses import dataclass
from pathlib import Path

from usar_replay.ros1.building import debian
from usar_replay.sandbox import (
    cgroup_v2,
    cgroups,
    container,
    cpu_sets,
    kernel_pools,
    kernel_sandbox,
)

__all__ = ["Finding", "check", "isolated", "warning"]


@dataclass(frozen=True, slots=True)
class Finding:
    """One part of the machine: whether a run gets it, and what that means."""

    name: str
    ok: bool
    said: str
    """What there is (``cgroup v1: memory, pids, cpuset writable``)."""
    means: str = ""
    """Where not ok: what it means for a run and its grade, and what to do."""
    fix: tuple[str, ...] = ()
    """Lines to show as they are (a file to write, the flags to run with), after :attr:`means`."""


_COSTS = {
    "memory": "no memory limit for a run as a whole (each process keeps its own)",
    "pids": "no process limit for a run as a whole (RLIMIT_NPROC instead)",
    "cpuset": "no CPU set per run: a neighbour can change a ROS 1 run's log, so run one at a "
    "time (--jobs 1)",
}


def _cgroup() -> Finding:
    got = cgroups.support()
    writable = got.writable
    if len(writable) == len(cgroups.CONTROLLERS):
        where = f" in {got.where}" if got.version == 2 else ""
        return Finding("cgroups", True, f"cgroup v{got.version}: memory, pids, cpuset{where}")
    missing = [c for c in cgroups.CONTROLLERS if c not in writable]
    shown = ", ".join(writable) or "none"
    said = f"cgroup v{got.version}: writable {shown}; not {', '.join(missing)}"
    costs = "; ".join(_COSTS[c] for c in missing)
    if got.version == 2 and got.user_manager and writable:
        # a user's systemd manager delegates what user@.service is given (stock: memory pids)
        return Finding(
            "cgroups",
            False,
            said,
            f"the user's systemd manager does not delegate {', '.join(missing)}: {costs}. To "
            "delegate it, as root write this file, run `systemctl daemon-reload`, and log in "
            "again:",
            (
                f"{cgroup_v2.DROP_IN_PATH}:",
                *(f"  {line}" for line in cgroup_v2.DROP_IN.splitlines()),
            ),
        )
    why = f" ({got.why})" if got.why else ""
    fix = (
        "in a container, run it with the flags the container line names"
        if os.geteuid() == 0
        else "run as root, or as a user whose systemd delegates cpuset memory pids"
    )
    return Finding("cgroups", False, said, f"without delegation{why}: {costs}; {fix}")


def _container() -> Finding:
    signs = container.read()
    name = container.kind(signs)
    if not name:
        return Finding("container", True, "none: usar runs on the machine itself")
    sandbox_ok, _ = kernel_sandbox.bwrap_available()
    got = cgroups.support()
    full = len(got.writable) == len(cgroups.CONTROLLERS)
    lacking = container.needs(
        signs, sandbox_ok=sandbox_ok, cgroups_ok=full, cgroup_version=got.version
    )
    if not lacking:
        return Finding("container", True, f"{name}: run with what the sandbox and cgroups need")
    seen: list[str] = []  # the signs of what is refused, each where its part is missing
    if not sandbox_ok:
        seen += [
            *(["a seccomp filter"] if signs.seccomp == 2 else []),
            *([f"AppArmor {signs.apparmor}"] if signs.apparmor else []),
            *(["/proc masked"] if signs.proc_masked else []),
        ] or ["its runtime refuses what the sandbox needs"]
    if not full:
        seen.append(
            "/sys/fs/cgroup read-only" if signs.cgroup_read_only else "cgroups not writable"
        )
    costs = "; ".join(
        [
            *(["without the sandbox usar batch refuses to grade"] if not sandbox_ok else []),
            *(["without cgroups, run one at a time (--jobs 1)"] if not full else []),
        ]
    )
    how = (
        "this flag; beside it"
        if len(lacking) == 1
        else "these flags (--privileged alone gives them all); beside each"
    )
    width = max(len(n.docker) for n in lacking)
    return Finding(
        "container",
        False,
        f"{name}: {', '.join(seen)}",
        f"run the container with {how}, what a run lacks without it. "
        + costs[:1].upper()
        + costs[1:],
        (
            *(f"{n.docker.ljust(width)}  {n.cost}" for n in lacking),
            "Kubernetes, the container's securityContext:",
            *(f"  {n.kubernetes}" for n in lacking),
        ),
    )


def _cpus() -> Finding:
    usable = cpu_sets.usable_cpus()
    if usable:
        return Finding("CPU sets", True, f"{len(usable)} CPUs to share out, one set per run")
    return Finding(
        "CPU sets",
        False,
        "no cpuset cgroup usar can write (the cgroups line says why)",
        "runs share every CPU: a ROS 1 run's log may depend on what else runs; run one at a time",
    )


def _realtime() -> Finding:
    soft, _hard = resource.getrlimit(resource.RLIMIT_RTPRIO)
    if os.geteuid() == 0 or soft > 0:
        return Finding("real-time priority", True, "SCHED_RR for a ROS 1 graph's threads")
    return Finding(
        "real-time priority",
        False,
        "not root and RLIMIT_RTPRIO is 0",
        "a ROS 1 graph is paced without SCHED_RR: on a busy machine more ticks reach their "
        "wall cap (a repeatability warning in the log)",
    )


def _sandbox() -> Finding:
    ok, why = kernel_sandbox.bwrap_available()
    if ok:
        return Finding(
            "kernel sandbox", True, "bubblewrap: user, PID, IPC, mount and network namespaces"
        )
    if not kernel_sandbox.installed():
        fix = f"{kernel_sandbox.INSTALL_HINT}; allow user namespaces; in a container, the flags "
        fix += "its line names"
    elif container.kind(container.read()):  # installing it again would change nothing
        fix = "bubblewrap is installed: run this container with the flags the container line names"
    else:
        fix = "bubblewrap is installed: allow user namespaces"
    return Finding(
        "kernel sandbox",
        False,
        why or "bubblewrap cannot make its sandbox here",
        f"missions would run outside a sandbox: usar batch refuses to ({fix})",
    )


def _ros1() -> Finding:
    missing = debian.missing()
    if not missing:
        return Finding("ROS 1", True, "Debian 12's ROS 1 packages for --ros1")
    return Finding(
        "ROS 1",
        False,
        f"{len(missing)} Debian packages missing",
        f"--ros1 and ROS 1 teams cannot run: apt-get update && {debian.install_line(missing)}",
    )


def _folders() -> Finding:
    if os.geteuid() == 0:  # what RunFolder and BuildFolder need to mount their tmpfs
        return Finding(
            "size-limited folders",
            True,
            "a tmpfs for each run folder (--run-folder) and build (--build-folder)",
        )
    return Finding(
        "size-limited folders",
        False,
        "not root: no tmpfs can be mounted",
        "a run's and a build's files have a per-file limit only: a team can fill the disk "
        "(run as root)",
    )


def _pools() -> Finding:
    bounded = kernel_pools.pool_limits_available()
    refused = kernel_pools.keyring_filter() is not None
    share = kernel_pools.PoolLimits().inotify_instances
    host = _read_int("/proc/sys/user/max_inotify_instances")
    if bounded and refused:
        return Finding(
            "kernel pools", True, f"inotify {share} of the host user's {host} a run, no keys"
        )
    missing = [
        *([] if bounded else ["inotify and fanotify (unshare --user failed)"]),
        *([] if refused else ["keys (no libseccomp2)"]),
    ]
    fix = [] if refused else ["apt-get install libseccomp2"]
    if not bounded and container.kind(container.read()):  # user namespaces: the run's flags
        fix.append("run this container with the flags the container line names")
    elif not bounded:
        fix.append("apt-get install util-linux; allow user namespaces")
    return Finding(
        "kernel pools",
        False,
        f"not bounded per run: {', '.join(missing)}",
        "one run can take the host user's pool every run shares, and another run's call "
        f"then fails: run one at a time ({'; '.join(fix)})",
    )


def _read_int(path: str) -> int | None:
    try:
        return int(Path(path).read_text().strip())
    except (OSError, ValueError):
        return None


def check() -> list[Finding]:
    """Every part, in the order ``usar doctor`` prints them."""
    return [
        _sandbox(),
        _container(),
        _cgroup(),
        _cpus(),
        _realtime(),
        _folders(),
        _pools(),
        _ros1(),
    ]


def isolated(findings: list[Finding]) -> bool:
    """Whether a run gets all of its isolation here (ROS 1 aside: its check is its own)."""
    return all(f.ok for f in findings if f.name != "ROS 1")


def warning(findings: list[Finding] | None = None) -> str:
    """One line for ``usar batch`` where isolation is partial ('' where it is whole)."""
    findings = check() if findings is None else findings
    partial = [f for f in findings if not f.ok and f.name != "ROS 1"]
    if not partial:
        return ""
    first = partial[0]
    return (
        f"usar: warning: isolation is partial here ({', '.join(f.name for f in partial)}): "
        f"{first.means}; `usar doctor` says more"
    )
