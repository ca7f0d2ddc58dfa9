"""The one reader of ``/proc/self/mountinfo`` (usar_replay/sandbox/mountinfo.py)."""

from __future__ import annotations

from usar_replay.sandbox import mountinfo

TEXT = (
    "36 25 0:31 /docker/4f2a /sys/fs/cgroup/memory ro,nosuid shared:15 - cgroup cgroup "
    "rw,memory\n"
    "30 23 0:26 / /sys/fs/cgroup rw,nosuid - cgroup2 cgroup2 rw,nsdelegate\n"
    "41 30 0:40 / /tmp/a\\040b\\134c rw - tmpfs tmpfs rw,size=512k\n"
    "not a mountinfo line\n"
)


def test_each_line_is_its_fields_with_the_escapes_undone() -> None:
    memory, unified, tmp = mountinfo.parse(TEXT)
    assert (memory.root, memory.point, memory.fstype) == (
        "/docker/4f2a", "/sys/fs/cgroup/memory", "cgroup",
    )  # fmt: skip
    assert memory.options == ("ro", "nosuid") and memory.super_options == ("rw", "memory")
    assert (unified.point, unified.fstype, unified.root) == ("/sys/fs/cgroup", "cgroup2", "/")
    assert tmp.point == "/tmp/a b\\c"


def test_this_processs_own_file_reads_and_parses() -> None:
    points = [m.point for m in mountinfo.parse(mountinfo.read())]
    assert "/" in points and "/proc" in points
