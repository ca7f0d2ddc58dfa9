"""On the real thing (issue 49): a stock Debian 12 machine, systemd 252 as PID 1 and the unified
cgroup v2 hierarchy, booted as a VM by ``../shared/vm/run.sh`` with a copy of this checkout.

``python -m pytest -m vm`` runs these four; nothing else does (tests/vm/conftest.py):

* as root on the image with the README's apt packages and the dependencies' venv baked in
  (``debian12-usar-venv``): the checkout installed, ``usar doctor`` says ``ok`` on every line,
  and the isolation tests that grades rest on pass there, not skipped, selected by node id:
  the sandbox's own (:data:`INNER`: the cgroup v2 backend, CPU sets, the kernel's OOM record)
  in one pytest process, then in a fresh one the red-team runs (:data:`RUNS`: a run's memory
  bound as a whole, its process bound, its own CPU set, one ROS 1 team's log the same bytes
  alone and beside a spinning neighbour under ``usar batch --jobs 2``);
* on the bare base image (``debian12``) with python3-venv removed, as a fresh install has it:
  the README's test command as written up to ``python -m pytest`` (its apt line, the venv,
  ``pip install '.[test]'`` from the host's wheelhouse, which holds the same files as PyPI), then
  the built-in mission recorded for 5 sim-seconds on the tests' one-room world and replayed with
  ``--grade`` (the README's first command, on a world small enough for emulation), ``usar
  doctor``, and the course's ROS 1 package built and recorded there;
* Debian's docker.io in the VM (cgroup v2, systemd's cgroup driver): ``usar doctor`` in a
  container with Docker's defaults names the flags a run needs, with exactly those (and with
  ``--privileged`` alone) every line is ok, and a recording made there replays bit for bit;
* as a user without root, logged in over ssh: ``usar doctor`` names the controller a stock
  ``user@.service`` does not delegate and the drop-in that adds it; with that drop-in, the
  cgroups come through the user's own systemd manager, and a recording replays bit for bit.

All run under TCG emulation here (the hosts' KVM cannot boot a stock kernel). Measured on
2026-12-02 (docs/batch.md has each step): the isolation check 15-25 min (the red-team runs 12-19
of them), the README's commands 86 min (the apt line 49), Docker 4 min, the user without root 6
min. The images are built beforehand (``vmtools.missing`` names the command); without them
each test fails with that one line.
"""

from __future__ import annotations

import shlex
from pathlib import Path

import pytest
import vmtools
from conftest import one_room

from usar_replay.world.scenario_toml import save

pytestmark = pytest.mark.vm
ANY = tuple(range(256))
"""Exit codes a step may end with and the script go on (its own assertion comes after)."""

_V2 = "tests/sandbox/test_cgroup_v2.py::test_"
_SETS = "tests/sandbox/test_cpu_sets.py::test_"
_LIMITS = "tests/redteam/test_run_limits.py::test_"
_OOM = (
    "tests/sandbox/test_kernel_sandbox.py::"
    "test_a_kill_is_called_out_of_memory_only_on_the_kernels_record"
)
INNER = (
    # the cgroup v2 backend itself (they skip on cgroup v1 machines, saying so)
    f"{_V2}usar_moves_itself_into_a_leaf_and_enables_the_controllers",
    f"{_V2}a_runs_memory_is_bound_as_a_whole",
    f"{_V2}a_run_under_its_memory_limit_is_not_out_of_memory",
    f"{_V2}a_runs_processes_are_bound_as_a_whole",
    f"{_V2}closing_a_run_kills_what_is_left_and_removes_its_cgroup",
    f"{_V2}each_run_gets_cpus_of_its_own_in_its_one_cgroup",
    "tests/sandbox/test_cgroups.py::test_a_run_gets_its_groups_and_loses_them",
    f"{_SETS}two_claims_never_share_a_cpu_and_a_release_gives_it_back",
    f"{_SETS}the_recorder_is_pinned_to_its_runs_cpus_and_restored",
    f"{_SETS}a_process_in_the_set_cannot_widen_its_cpus",
    f"{_SETS}a_set_whose_owner_is_gone_is_removed_by_the_next_claim",
    f"{_OOM}[True]",
    f"{_OOM}[False]",
    "tests/cli/commands/test_doctor.py::test_doctor_says_each_part",
)
"""The sandbox's own tests run inside the VM: each must pass there (a skip fails the check)."""

RUNS = (
    # whole runs through the recorder and `usar batch`, as a class is graded
    f"{_LIMITS}a_memory_hog_over_children_and_tmpfs_is_out_of_memory",
    f"{_LIMITS}a_fork_bomb_is_refused_at_the_process_limit",
    f"{_LIMITS}a_mission_cannot_leave_its_cpu_set_or_see_its_cgroup",
    "tests/redteam/test_isolation.py::test_a_teams_log_is_the_same_whoever_runs_beside_it",
)
"""The red-team runs, in a pytest process of their own (a fresh process, as `usar` is)."""

RENDERER = (
    "import pkgutil, pybullet as p; p.connect(p.DIRECT); "
    "print('egl plugin', p.loadPlugin(pkgutil.get_loader('eglRenderer').get_filename(), "
    "'_eglRendererPlugin'))"
)
"""Says in the log whether pybullet's EGL renderer loads in a fresh process (diagnosis only)."""

NO_EGL = ".no-egl"
"""A folder (in the copy of the checkout) whose ``eglRenderer.py`` hides pybullet's EGL plugin
from ``pkgutil`` in the VM, so a recorder falls back to pybullet's own (tiny) renderer, as where
the plugin does not load. Why: on qemu's emulated CPU (TCG, ``-cpu max``) the plugin died with
SIGSEGV on load, in a fresh process, right after ``GL_RENDERER=llvmpipe (LLVM 15.0.6, 256
bits)``, and as well with ``LP_NATIVE_VECTOR_WIDTH=128``; with ``GALLIUM_DRIVER=softpipe`` it
could not create a context and ended the process (exit 1). The same packages on this host load
it; the ``renderer`` step says in the log what the VM does."""


def _hide_egl(folder: Path) -> str:
    """The environment assignment that hides the EGL plugin (see :data:`NO_EGL`)."""
    (folder / NO_EGL).mkdir()
    (folder / NO_EGL / "eglRenderer.py").write_text("# not a plugin: the tiny renderer instead\n")
    return f"PYTHONPATH={folder / NO_EGL}"


FACTS = "stat -fc %T /sys/fs/cgroup && ps -o comm= -p 1 && systemctl --version | head -1"
"""What makes the VM the machine issue 49 is about: cgroup2fs, systemd as PID 1."""


def _fail_without(image: str, wheelhouse: bool = False) -> None:
    why = vmtools.missing(image, wheelhouse)
    if why:
        pytest.fail(why, pytrace=False)


def _ran_on_the_real_thing(run: vmtools.VmRun) -> dict[str, str]:
    """Each step's output by name, once the script ran to its end (its timings printed) on the
    machine issue 49 is about (its ``facts`` step: cgroup2fs, systemd as PID 1)."""
    print(run.timings())
    assert run.rc == 0, run.tail()
    facts = run.steps["facts"].output.split()
    assert facts[:2] == ["cgroup2fs", "systemd"], run.tail()
    return {name: step.output for name, step in run.steps.items()}


def test_isolation_holds_as_root_on_a_stock_debian12(tmp_path: Path) -> None:
    _fail_without(vmtools.VENV_IMAGE)
    folder = vmtools.copy_checkout(tmp_path / "usar-replay")
    venv = "PATH=/opt/venv/bin:$PATH"
    pytest = f"{_hide_egl(folder)} {venv} python -m pytest -p no:cacheprovider -n 0 -m '' -q -rs"
    script = "".join([
        vmtools.step("facts", FACTS),
        vmtools.step("install", "/opt/venv/bin/pip install -q --no-deps --no-build-isolation ."),
        vmtools.step("doctor", "/opt/venv/bin/usar doctor", (0, 1)),
        vmtools.step("sandbox", f"{pytest} {' '.join(map(shlex.quote, INNER))}", ANY),
        vmtools.step("renderer", f"{venv} python -c {shlex.quote(RENDERER)}", ANY),
        vmtools.step("runs", f"{pytest} {' '.join(map(shlex.quote, RUNS))}", ANY),
    ])  # fmt: skip
    run = vmtools.run_in_vm(folder, script, vmtools.VENV_IMAGE, timeout_s=5400)
    _ran_on_the_real_thing(run)
    doctor = run.steps["doctor"]
    assert doctor.rc == 0 and vmtools.doctor_all_ok(doctor.output), doctor.output
    for name, ids in (("sandbox", INNER), ("runs", RUNS)):
        tests = run.steps[name]
        counts = vmtools.pytest_counts(tests.output)
        assert tests.rc == 0 and counts == {"passed": len(ids)}, (
            f"{run.steps['renderer'].output}\n{tests.output[-6000:]}"
        )


def test_the_readmes_commands_work_on_a_fresh_debian12(tmp_path: Path) -> None:
    _fail_without(vmtools.BASE_IMAGE, wheelhouse=True)
    apt, install = vmtools.readme_test_command()
    folder = vmtools.copy_checkout(tmp_path / "usar-replay")
    save(one_room(), folder / "room.toml")
    usar = f". .venv/bin/activate && {_hide_egl(folder)} usar"
    script = "".join([
        vmtools.step("facts", FACTS),
        # the image adds python3-venv for its own tools; a stock Debian 12 has no ensurepip
        vmtools.step(
            "fresh",
            "apt-get purge -qy python3-venv python3.11-venv >/dev/null && apt-get autoremove "
            "-qy --purge >/dev/null && ! python3.11 -m venv /tmp/probe",
        ),
        vmtools.step("apt", apt),
        vmtools.step("install", install),
        vmtools.step(
            "record",
            f"{usar} record --scenario room.toml --max-sim-time 5 --out recordings/room.mcap",
            (1,),  # stopped at --max-sim-time
        ),
        vmtools.step("replay", f"{usar} replay --grade recordings/room.mcap", (0, 1)),
        vmtools.step("doctor", f"{usar} doctor", (0, 1)),
        vmtools.step(
            "ros1",
            f"{usar} record --scenario room.toml --ros1 examples/ros1/usar_course "
            "--max-sim-time 5 --out recordings/ros1.mcap",
            (1,),
        ),
    ])  # fmt: skip
    run = vmtools.run_in_vm(
        folder, script, vmtools.BASE_IMAGE, timeout_s=5400, wheelhouse=vmtools.WHEELHOUSE
    )
    said = _ran_on_the_real_thing(run)
    assert "Recorded recordings/room.mcap" in said["record"], said["record"]
    assert "Replay reproduces the recording bit for bit." in said["replay"], said["replay"]
    assert "Total: " in said["replay"], said["replay"]
    assert vmtools.doctor_all_ok(said["doctor"]), said["doctor"]
    assert "Recorded recordings/ros1.mcap" in said["ros1"], said["ros1"]
    assert "Pacing: " in said["ros1"], said["ros1"]


IMAGE_ROOT = (
    "set -e; mkdir -p /tmp/img && cd /tmp/img && mkdir -p tmp var/tmp root run proc sys dev etc "
    "usr opt work && chmod 1777 tmp var/tmp && for d in bin lib lib64 sbin; do ln -sfn usr/$d $d; "
    "done && tar -c . | docker import - usar:vm >/dev/null && docker image ls usar:vm"
)
"""A container image of the VM's own system without copying it: a root of empty folders (and
Debian 12's merged-/usr links) that each run binds the VM's ``/usr``, ``/opt`` (the venv with
usar installed) and ``/etc`` into, read-only. What the container gets from Docker (its seccomp
filter, AppArmor profile, masked ``/proc``, read-only or private cgroup fs, capabilities) is
Docker's, as in any image."""


def _docker(flags: str, command: str, folder: Path) -> str:
    """``docker run`` of ``command`` in the VM's own system, with ``flags``, the checkout at
    /work (read-only) and the EGL plugin hidden as in the VM (:data:`NO_EGL`)."""
    binds = f"-v /usr:/usr:ro -v /opt:/opt:ro -v /etc:/etc:ro -v {folder}:/work:ro"
    env = f"-e PYTHONPATH=/work/{NO_EGL} -e PATH=/opt/venv/bin:/usr/bin:/usr/sbin -w /tmp"
    return f"docker run --rm {flags} {binds} {env} usar:vm {command}"


NAMED = r"grep -oE -- '--(security-opt [a-z]+=unconfined|privileged( --cgroupns=private)?)'"
"""The ``docker run`` flags a ``usar doctor`` output names (its container line's table)."""


def test_docker_on_a_stock_debian12_says_what_it_needs_and_runs_with_it(tmp_path: Path) -> None:
    """Docker (Debian's docker.io) on the cgroup v2 host: with Docker's defaults ``usar doctor``
    recognises the container and names the flags a run needs (exit 1); with exactly the flags
    it named, and with ``--privileged`` alone, every line is ok (the v2 backend in the
    container's own cgroup namespace: usar moves the container's processes into a leaf and
    enables the controllers below it), and a recording there replays bit for bit."""
    _fail_without(vmtools.VENV_IMAGE)
    folder = vmtools.copy_checkout(tmp_path / "usar-replay")
    _hide_egl(folder)
    save(one_room(), folder / "room.toml")
    doctor = "usar doctor"
    stock = _docker("", doctor, folder)  # its exit code, not tee's (pipefail)
    record = (
        "bash -c 'usar record --scenario /work/room.toml --max-sim-time 2 --out /tmp/r.mcap; "
        "usar replay --grade /tmp/r.mcap'"
    )
    script = "".join([
        vmtools.step("facts", FACTS),
        vmtools.step("install", "/opt/venv/bin/pip install -q --no-deps --no-build-isolation ."),
        vmtools.step(
            "docker",
            "apt-get update -q >/dev/null && DEBIAN_FRONTEND=noninteractive apt-get install -qy "
            "--no-install-recommends docker.io >/dev/null && docker version --format "
            "'{{.Server.Version}} {{.Server.Os}}' && docker info --format '{{.CgroupVersion}} "
            "{{.CgroupDriver}}'",
        ),
        vmtools.step("image", IMAGE_ROOT),
        vmtools.step("defaults", f"set -o pipefail; {stock} | tee /tmp/defaults", (0, 1, 2)),
        vmtools.step("flags", f"{NAMED} /tmp/defaults | sort -u | tr '\\n' ' ' | tee /tmp/flags"),
        vmtools.step("named", _docker("$(cat /tmp/flags)", doctor, folder), (0, 1, 2)),
        vmtools.step("privileged", _docker("--privileged", doctor, folder), (0, 1, 2)),
        vmtools.step("record", _docker("--privileged", record, folder), ANY),
    ])  # fmt: skip
    run = vmtools.run_in_vm(folder, script, vmtools.VENV_IMAGE, timeout_s=3600)
    said = _ran_on_the_real_thing(run)
    assert said["docker"].split()[-2:] == ["2", "systemd"], said["docker"]  # v2, systemd driver
    defaults = said["defaults"]
    assert run.steps["defaults"].rc == 1 and "docker" in defaults, defaults
    assert "--privileged" in defaults and "securityContext" in defaults, defaults
    assert "--privileged" in said["flags"], said["flags"]  # the flags doctor named, then run
    for name in ("named", "privileged"):
        assert run.steps[name].rc == 0 and vmtools.doctor_all_ok(said[name]), said[name]
    assert "Replay reproduces the recording bit for bit." in said["record"], said["record"]


STUDENT = "student"
AS_STUDENT = (
    "ssh -q -i /root/.ssh/student -o BatchMode=yes -o StrictHostKeyChecking=no "
    f"-o UserKnownHostsFile=/dev/null {STUDENT}@localhost"
)
"""A login of a user without root, as a student has one: ssh, so PAM and systemd-logind give
it a session scope and start the user's own systemd manager (``user@UID.service``)."""

NEW_USER = (
    f"useradd -m {STUDENT} && install -d -m 700 -o {STUDENT} -g {STUDENT} /home/{STUDENT}/.ssh && "
    "ssh-keygen -q -t ed25519 -N '' -f /root/.ssh/student && install -m 600 -o "
    f"{STUDENT} -g {STUDENT} /root/.ssh/student.pub /home/{STUDENT}/.ssh/authorized_keys && "
    f"{AS_STUDENT} id -un && systemctl show -p DelegateControllers user@$(id -u {STUDENT}).service"
)

APPLY_DROP_IN = (
    "f=$(grep -oE '/etc/systemd/system/[^ ]+\\.conf' /tmp/stock | head -1) && test -n \"$f\" && "
    'mkdir -p "$(dirname "$f")" && awk -v f="$f:" '
    "'p && /^  +[^ ]/ {sub(/^ +/, \"\"); print; next} {p = 0} index($0, f) {p = 1}' /tmp/stock "
    f'> "$f" && cat "$f" && systemctl daemon-reload && systemctl stop user@$(id -u {STUDENT})'
    ".service"
)
"""Writes exactly the drop-in the stock ``usar doctor`` named (its path, then its indented
lines), reloads systemd and stops the user's manager, so the next login starts it anew."""


def test_a_user_without_root_gets_what_their_systemd_delegates(tmp_path: Path) -> None:
    """A user without root, logged in over ssh: on a stock ``user@.service`` (which delegates
    ``memory pids``, not ``cpuset``) ``usar doctor`` names the missing controller and the exact
    drop-in; with that drop-in written as it says (and a new login), the cgroups line is ok
    through the user's own manager (a transient scope, ``Delegate=yes``), as is the CPU sets
    line, and a recording made as that user replays bit for bit."""
    _fail_without(vmtools.VENV_IMAGE)
    folder = vmtools.copy_checkout(tmp_path / "usar-replay")
    _hide_egl(folder)
    save(one_room(), folder / "room.toml")
    shared = "/tmp/shared"  # the user's readable copy of the world and the EGL hider
    doctor = f"{AS_STUDENT} /opt/venv/bin/usar doctor"
    record = (
        f"{AS_STUDENT} 'cd ~ && export PATH=/opt/venv/bin:$PATH PYTHONPATH={shared}/{NO_EGL} && "
        f"usar record --scenario {shared}/room.toml --max-sim-time 2 --out s.mcap; "
        "usar replay --grade s.mcap'"
    )
    script = "".join([
        vmtools.step("facts", FACTS),
        vmtools.step("install", "/opt/venv/bin/pip install -q --no-deps --no-build-isolation ."),
        vmtools.step("user", NEW_USER),
        vmtools.step(
            "share",
            f"mkdir -p {shared} && cp -r room.toml {NO_EGL} {shared}/ && chmod -R a+rX {shared}",
        ),
        vmtools.step("stock", f"{doctor} | tee /tmp/stock", (0, 1, 2)),
        vmtools.step("drop-in", APPLY_DROP_IN),
        vmtools.step("delegated", doctor, (0, 1, 2)),
        vmtools.step("record", record, ANY),
    ])  # fmt: skip
    run = vmtools.run_in_vm(folder, script, vmtools.VENV_IMAGE, timeout_s=2400)
    said = _ran_on_the_real_thing(run)
    assert said["user"].splitlines()[0] == STUDENT, said["user"]
    stock = _line(said["stock"], "cgroups")
    assert stock.startswith("MISS") and "cpuset" in stock, said["stock"]
    assert "writable memory, pids" in stock, said["stock"]  # what user@.service delegates
    assert "user@.service.d/delegate.conf:" in said["stock"], said["stock"]
    assert "Delegate=" in said["drop-in"] and "cpuset" in said["drop-in"], said["drop-in"]
    delegated = said["delegated"]
    for name in ("kernel sandbox", "cgroups", "CPU sets"):
        assert _line(delegated, name).startswith("ok"), delegated
    assert "memory, pids, cpuset in usar-" in _line(delegated, "cgroups"), delegated
    assert "Delegate=yes" in _line(delegated, "cgroups"), delegated
    assert "Replay reproduces the recording bit for bit." in said["record"], said["record"]


def _line(doctor: str, name: str) -> str:
    """``usar doctor``'s line for the part ``name`` (its mark and what it says)."""
    for line in doctor.splitlines():
        if line[5:].startswith(f"{name}  "):
            return line
    raise AssertionError(f"no {name!r} line in:\n{doctor}")
