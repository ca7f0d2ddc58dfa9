"""The VM check's own reading of a script's output (tests/vmtools.py), checked without a VM:
a misread step fails the VM check hours later, on a slow machine."""

from __future__ import annotations

import vmtools


def test_each_step_is_read_with_its_output_and_exit_code() -> None:
    text = "\n".join([
        "[vm] ready",
        "@@start facts",
        "cgroup2fs",
        "@@step facts rc=0 s=1",
        "@@start flags",
        "--privileged --cgroupns=private @@step flags rc=0 s=0",  # no final newline
        "@@start doctor",
        "MISS cgroups",
        "@@step doctor rc=1 s=8",
    ])  # fmt: skip
    steps = vmtools.steps_of(text)
    assert list(steps) == ["facts", "flags", "doctor"]
    assert steps["facts"].output == "cgroup2fs" and steps["facts"].rc == 0
    assert steps["flags"].output == "--privileged --cgroupns=private "
    assert (steps["doctor"].rc, steps["doctor"].output) == (1, "MISS cgroups")
