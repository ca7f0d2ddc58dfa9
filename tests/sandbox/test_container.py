"""sandbox/container: a container recognised from the files its runtime leaves, and the run
flags its sandbox and cgroups need, judged on each shape's own texts."""

from __future__ import annotations

from usar_replay.sandbox import container
from usar_replay.sandbox.container import (
    APPARMOR,
    CGROUPS,
    CGROUPS_PRIVATE,
    SECCOMP,
    SYSTEMPATHS,
)

# /proc/self/mountinfo of Docker's defaults: masked /proc paths, a read-only cgroup fs
DOCKER_MOUNTS = """\
612 590 0:55 / / rw,relatime - overlay overlay rw
613 612 0:58 / /proc rw,nosuid,nodev,noexec,relatime - proc proc rw
619 615 0:29 / /sys/fs/cgroup ro,nosuid,nodev,noexec,relatime - cgroup2 cgroup rw
591 613 0:59 /bus /proc/bus ro,nosuid,nodev,noexec,relatime - proc proc rw
597 613 0:60 / /proc/kcore rw,nosuid - tmpfs tmpfs rw,size=0k
"""
# Docker 20.10's defaults on a cgroup v1 host (measured; options abridged): a writable tmpfs
# holding read-only controller mounts, each showing the container's folder of the host's tree
ID = "8c0ff6ccf4db4701620e04ba21028ae389c03beee3696205efe9e9852062cdb7"
DOCKER_V1_MOUNTS = f"""\
112 111 0:53 / /proc rw,nosuid,nodev,noexec,relatime - proc proc rw
116 115 0:57 / /sys/fs/cgroup rw,nosuid,nodev,noexec,relatime - tmpfs tmpfs rw,mode=755
120 116 0:32 /docker/{ID} /sys/fs/cgroup/memory ro,nosuid,nodev,noexec - cgroup cgroup rw,memory
124 116 0:36 /docker/{ID} /sys/fs/cgroup/pids ro,nosuid,nodev,noexec - cgroup cgroup rw,pids
56 112 0:53 /bus /proc/bus ro,nosuid,nodev,noexec,relatime - proc proc rw
"""
DOCKER_V1_CGROUP = f"4:memory:/docker/{ID}\n8:pids:/docker/{ID}\n0::/docker/{ID}\n"
HOST_MOUNTS = """\
22 1 8:1 / / rw,relatime - ext4 /dev/sda1 rw
24 22 0:22 / /proc rw,nosuid,nodev,noexec,relatime - proc proc rw
26 25 0:25 / /sys/fs/cgroup rw,nosuid,nodev,noexec,relatime - cgroup2 cgroup2 rw
"""


def test_dockers_defaults_need_all_four() -> None:
    signs = container.signs_from(
        files={"/.dockerenv": True},
        status="Name:\tsh\nSeccomp:\t2\nSeccomp_filters:\t1\n",
        apparmor="docker-default (enforce)\n",
        mountinfo=DOCKER_MOUNTS,
        proc_cgroup="0::/\n",
    )
    assert container.kind(signs) == "docker"
    assert signs.seccomp == 2 and signs.apparmor == "docker-default (enforce)"
    assert signs.proc_masked and signs.cgroup_read_only
    assert container.needs(signs, sandbox_ok=False, cgroups_ok=False) == [
        SECCOMP, APPARMOR, SYSTEMPATHS, CGROUPS,
    ]  # fmt: skip
    assert SECCOMP.docker == "--security-opt seccomp=unconfined"
    assert APPARMOR.docker == "--security-opt apparmor=unconfined"
    assert SYSTEMPATHS.docker == "--security-opt systempaths=unconfined"
    assert "Unconfined" in SECCOMP.kubernetes and SYSTEMPATHS.kubernetes == "procMount: Unmasked"


def test_the_security_opts_given_leave_the_cgroups() -> None:
    signs = container.signs_from(
        files={"/.dockerenv": True},
        status="Seccomp:\t0\n",
        apparmor="unconfined\n",
        mountinfo=DOCKER_MOUNTS.replace("/proc/kcore", "/dev/shm").replace("/proc/bus", "/x"),
    )
    assert not signs.proc_masked and signs.apparmor == ""
    assert container.needs(signs, sandbox_ok=True, cgroups_ok=False) == [CGROUPS]
    assert container.needs(signs, sandbox_ok=True, cgroups_ok=True) == []


def test_a_sandbox_refused_without_a_sign_names_all_three() -> None:
    signs = container.signs_from(files={"/run/.containerenv": True}, mountinfo=HOST_MOUNTS)
    assert container.needs(signs, sandbox_ok=False, cgroups_ok=True) == [
        SECCOMP, APPARMOR, SYSTEMPATHS,
    ]  # fmt: skip


def test_each_runtime_is_named() -> None:
    podman = container.signs_from(
        files={"/run/.containerenv": True}, pid1_environ=b"PATH=/bin\0container=podman\0"
    )
    assert container.kind(podman) == "podman" and podman.container_env == "podman"
    lxc = container.signs_from(files={}, pid1_environ=b"container=lxc\0HOME=/\0")
    assert container.kind(lxc) == "lxc"
    k8s = container.signs_from(files={}, environ={"KUBERNETES_SERVICE_HOST": "10.0.0.1"})
    assert container.kind(k8s) == "kubernetes"
    scope = container.signs_from(files={}, proc_cgroup="0::/system.slice/docker-ab12.scope\n")
    assert container.kind(scope) == "container"


def test_a_machine_of_its_own_is_no_container() -> None:
    signs = container.signs_from(
        files={"/.dockerenv": False},
        pid1_environ=b"HOME=/\0TERM=linux\0",
        proc_cgroup="0::/user.slice/user-0.slice/session-3.scope\n",
        status="Seccomp:\t0\n",
        mountinfo=HOST_MOUNTS,
    )
    assert container.kind(signs) == "" and not signs.cgroup_read_only


def test_v1s_read_only_controller_mounts_are_a_read_only_cgroup_fs() -> None:
    signs = container.signs_from(
        files={"/.dockerenv": True}, mountinfo=DOCKER_V1_MOUNTS, proc_cgroup=DOCKER_V1_CGROUP
    )
    assert signs.cgroup_read_only and signs.proc_masked and not signs.cgroupns_private
    privileged = DOCKER_V1_MOUNTS.replace(" ro,nosuid", " rw,nosuid").replace("/proc/bus", "/x")
    assert not container.signs_from(files={}, mountinfo=privileged).cgroup_read_only
    # systemd's v1 hosts mount the tmpfs read-only, their controllers' mounts writable
    systemd = "25 18 0:22 / /sys/fs/cgroup ro,nosuid - tmpfs tmpfs ro,mode=755\n" + privileged
    assert not container.signs_from(files={}, mountinfo=systemd).cgroup_read_only


def test_the_cgroups_need_privileged_and_a_namespace_only_where_v2_shows_the_hosts_paths() -> None:
    host_paths = container.signs_from(files={"/.dockerenv": True}, proc_cgroup=DOCKER_V1_CGROUP)
    private = container.signs_from(files={"/.dockerenv": True}, proc_cgroup="4:memory:/\n0::/\n")
    assert private.cgroupns_private and not host_paths.cgroupns_private
    assert CGROUPS.docker == "--privileged" and CGROUPS.kubernetes == "privileged: true"
    assert container.needs(host_paths, sandbox_ok=True, cgroups_ok=False) == [CGROUPS]
    for signs in (private, host_paths):  # v1: --privileged alone, either namespace (measured)
        assert container.needs(signs, sandbox_ok=True, cgroups_ok=False, cgroup_version=1) == [
            CGROUPS
        ]
    v2 = container.signs_from(files={}, proc_cgroup="0::/system.slice/docker-ab12.scope\n")
    assert container.needs(v2, sandbox_ok=True, cgroups_ok=False, cgroup_version=2) == [
        CGROUPS_PRIVATE
    ]
    assert "--cgroupns=private" in CGROUPS_PRIVATE.docker
    assert container.needs(private, sandbox_ok=True, cgroups_ok=False, cgroup_version=2) == [
        CGROUPS
    ]
