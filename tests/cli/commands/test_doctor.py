"""`usar doctor` (cli/commands/doctor): a line per part of the machine within 100 columns, what
a missing part means, exit 0 for a whole isolation and 1 for a partial one."""

from __future__ import annotations

import pytest

from usar_replay.cli.main import main
from usar_replay.sandbox import cgroups, container, cpu_sets, kernel_sandbox
from usar_replay.sandbox.cgroups import CONTROLLERS


def test_doctor_says_each_part(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["doctor"])
    out = capsys.readouterr().out
    assert code in (0, 1)
    for part in (
        "kernel sandbox",
        "container",
        "cgroups",
        "CPU sets",
        "real-time priority",
        "ROS 1",
    ):
        assert part in out
    assert all(len(line) <= 100 for line in out.splitlines())
    assert out.rstrip().endswith("isolation here" if code == 0 else "isolation is partial here")


def test_a_missing_part_exits_1_and_says_what_to_do(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(cpu_sets, "usable_cpus", lambda: [])
    assert main(["doctor"]) == 1
    out = capsys.readouterr().out
    assert "MISS CPU sets" in out and "run one at a time" in " ".join(out.split())


def _lines(out: str) -> list[str]:
    lines = out.splitlines()
    assert all(len(line) <= 100 for line in lines), [x for x in lines if len(x) > 100]
    return lines


def test_cgroup_v2_with_a_delegated_subtree_is_ok(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    where = "transient scope usar-7.scope (systemd, Delegate=yes)"
    monkeypatch.setattr(container, "read", lambda: container.Signs())
    monkeypatch.setattr(cgroups, "support", lambda: cgroups.Support(2, CONTROLLERS, where))
    main(["doctor"])
    line = next(x for x in _lines(capsys.readouterr().out) if x.split()[1:2] == ["cgroups"])
    assert line.startswith("ok   cgroups") and "cgroup v2: memory, pids, cpuset in" in line


def test_a_user_without_cpuset_is_given_the_drop_in(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    got = cgroups.Support(2, ("memory", "pids"), "transient scope", "cpuset not delegated", True)
    monkeypatch.setattr(cgroups, "support", lambda: got)
    monkeypatch.setattr(container, "read", lambda: container.Signs())
    assert main(["doctor"]) == 1
    lines = _lines(capsys.readouterr().out)
    text = " ".join(" ".join(lines).split())
    assert "MISS cgroups               cgroup v2: writable memory, pids; not cpuset" in lines
    assert "does not delegate cpuset" in text and "systemctl daemon-reload" in text
    assert "log in again" in text
    at = lines.index(next(x for x in lines if x.strip().endswith("delegate.conf:")))
    assert lines[at].strip() == "/etc/systemd/system/user@.service.d/delegate.conf:"
    assert [x.strip() for x in lines[at + 1 : at + 3]] == [
        "[Service]", "Delegate=cpu cpuset io memory pids",
    ]  # fmt: skip


def test_a_container_without_the_flags_names_each_and_its_cost(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    signs = container.Signs(
        dockerenv=True, seccomp=2, apparmor="docker-default (enforce)", proc_masked=True,
        cgroup_read_only=True,
    )  # fmt: skip
    monkeypatch.setattr(container, "read", lambda: signs)
    monkeypatch.setattr(kernel_sandbox, "bwrap_available", lambda: (False, "bwrap: no userns"))
    monkeypatch.setattr(cgroups, "support", lambda: cgroups.Support(2, (), "", "read-only"))
    assert main(["doctor"]) == 1
    lines = _lines(capsys.readouterr().out)
    text = " ".join(" ".join(lines).split())
    said = "docker: a seccomp filter, AppArmor docker-default (enforce), /proc masked, "
    assert f"MISS container {said}/sys/fs/cgroup read-only run the container" in text
    for flag, cost in [
        ("--security-opt seccomp=unconfined", "namespaces refused"),
        ("--security-opt apparmor=unconfined", "mounts refused"),
        ("--security-opt systempaths=unconfined", "/proc masked"),
        ("--privileged", "no per-run memory, pids, CPU set"),
    ]:
        assert any(flag in x and cost in x for x in lines), flag
    at = lines.index(next(x for x in lines if "Kubernetes" in x))
    kube = [x.strip() for x in lines[at + 1 : at + 5]]
    assert kube == [
        "seccompProfile: {type: Unconfined}", "appArmorProfile: {type: Unconfined}",
        "procMount: Unmasked", "privileged: true",
    ]  # fmt: skip
    # wherever the sandbox is said to be missing, no way around it is offered without its cost
    for x in lines:
        assert "--no-sandbox" not in x or "world key" in x, x


def test_a_container_with_the_sandbox_but_not_the_cgroups_says_the_cgroups_are_refused(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    signs = container.Signs(dockerenv=True, cgroup_read_only=True, cgroupns_private=True)
    monkeypatch.setattr(container, "read", lambda: signs)
    monkeypatch.setattr(kernel_sandbox, "bwrap_available", lambda: (True, ""))
    monkeypatch.setattr(cgroups, "support", lambda: cgroups.Support(1, ()))
    assert main(["doctor"]) == 1
    lines = _lines(capsys.readouterr().out)
    text = " ".join(" ".join(lines).split())
    line = next(x for x in lines if x.startswith("MISS container"))
    assert line.endswith("docker: /sys/fs/cgroup read-only") and "sandbox" not in line
    assert (
        "run the container with this flag; beside it, what a run lacks" in text
        and "refuses to grade" not in text
    )
    assert any("--privileged  no per-run memory, pids, CPU set" in x for x in lines)
    assert "--cgroupns" not in text and "privileged: true" in text
    monkeypatch.setattr(container, "read", lambda: container.Signs(dockerenv=True))
    main(["doctor"])
    line = next(x for x in _lines(capsys.readouterr().out) if x.startswith("MISS container"))
    assert line.endswith("docker: cgroups not writable")


def test_a_long_line_wraps_under_its_text_and_keeps_its_end(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    why = (
        "/usr/bin/bwrap cannot create namespaces here (bwrap: No permissions to create new "
        "namespace, likely because the kernel does not allow non-privileged user namespaces)"
    )
    signs = container.Signs(dockerenv=True, seccomp=2, proc_masked=True, cgroup_read_only=True)
    monkeypatch.setattr(container, "read", lambda: signs)
    monkeypatch.setattr(kernel_sandbox, "bwrap_available", lambda: (False, why))
    monkeypatch.setattr(cgroups, "support", lambda: cgroups.Support(1, ()))
    monkeypatch.setattr(
        container, "CGROUPS", container.Need("--privileged", "privileged: true", "x " * 60)
    )
    main(["doctor"])
    lines = _lines(capsys.readouterr().out)
    at = lines.index(next(x for x in lines if x.startswith("MISS kernel sandbox")))
    lead = lines[at].index("/usr/bin/bwrap")
    assert lines[at + 1].startswith(" " * lead) and lines[at + 1][lead] != " "
    said = " ".join(x.strip() for x in lines[at : at + 3])
    assert "user namespaces)" in said  # the reason's end, not cut at column 100
    # a flag's cost wraps under the cost column, not under the flag
    row = next(i for i, x in enumerate(lines) if x.strip().startswith("--privileged "))
    column = lines[row].index("x x")
    assert lines[row + 1].startswith(" " * column + "x")
    kube = next(i for i, x in enumerate(lines) if x.strip().startswith("Kubernetes, the"))
    assert kube > row + 1 and all(x[column:].startswith("x") for x in lines[row + 1 : kube])


def test_no_container_is_ok(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(container, "read", lambda: container.Signs())
    main(["doctor"])
    assert "ok   container" in capsys.readouterr().out
