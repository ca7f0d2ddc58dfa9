"""Red team: one run cannot touch another (issue #33, point 1): a team's log is the same
whoever runs beside it.

The course example package (``examples/ros1/usar_course``) is recorded on the one-room world
alone (``usar record --ros1``), then graded by ``usar batch --jobs 2`` twice: beside a copy of
itself, and beside a Python team that burns CPU (a thread that spins and asks for every CPU,
and a busy timer callback). Every message of every one of the package's logs must be the same
bytes at the same log time: each run has its own CPU set (usar_replay/sandbox/cpu_sets.py), the
graph's real-time priority never leaves it, and pacing follows the graph, not the machine.

Needs bubblewrap, Debian's ROS 1 and root (the CPU sets). Every run stops at
:data:`SIM_S` of sim time (the explorer is on its way to its first target, some 3,000
messages): four ROS 1 runs and a build in about a minute, so CI runs it.
"""

from __future__ import annotations

import hashlib
import json
import shutil
import time
from pathlib import Path

import pytest
from clitools import run_batch, usar
from conftest import one_room

from usar_replay.log import bag
from usar_replay.ros1.building import debian
from usar_replay.sandbox import cpu_sets
from usar_replay.sandbox.kernel_sandbox import bwrap_available
from usar_replay.world.scenario_toml import save

ROOT = Path(__file__).resolve().parents[2]
COURSE = ROOT / "examples" / "ros1" / "usar_course"
SLOW_OK = ("--build-timeout", "3600", "--connect-timeout", "600", "--rtf", "0.02")
"""Wall limits wide enough for a slow machine (the Debian 12 VM under emulation: its build once
passed 900 s, a run of the pair once ended at its first tick, the graph's 60 s to connect the
likely cause, and a tick's default wall cap of dt / 0.5 = 100 ms is passed there): they change
no message, and here nothing comes near them (every run's capped ticks are in what a failed
comparison says)."""
SIM_S = "20"
"""Sim seconds of every run (``--max-sim-time``): enough ticks for pacing and scheduling to
show, short enough for the fast suite."""

SPINNER = """
import os, threading, time

from usar_replay.api import Node

START = time.monotonic()
SPIN_S = {spin_s}  # the honest team's batch beside itself, and 5 s: this run lasts as long


def spinning() -> bool:
    return time.monotonic() - START < SPIN_S


def spin() -> None:
    try:
        os.sched_setaffinity(0, range(os.cpu_count() or 1))
    except OSError:
        pass
    while spinning():
        pass


class Spinner(Node):
    def __init__(self) -> None:
        super().__init__("spinner")
        self.create_timer(0.1, self.burn)

    def burn(self) -> None:
        t0 = time.monotonic()  # each call burns up to 1 s (the tick timeout is 10 s)
        while spinning() and time.monotonic() - t0 < 1.0:
            pass


def main() -> None:
    threading.Thread(target=spin, daemon=True).start()
    Spinner()
"""
"""A team that burns CPU for as long as its neighbour runs: a thread that spins and asks for
every CPU, and a timer whose callback spins too, which keeps its run going (200 calls of up to
1 s for 20 sim-s) until ``SPIN_S`` of wall time have passed. ``SPIN_S`` is sized from the batch
of the honest team beside itself (its build cached, as in the spinner's batch), so the two runs
overlap on a fast machine and under emulation alike."""


def _ready() -> str:
    if not bwrap_available()[0]:
        return "no kernel sandbox here"
    if len(cpu_sets.usable_cpus()) < 2:  # runs wait for CPUs others hold, never skip for it
        return "fewer than 2 CPUs with cpuset cgroups here (root, cgroup v1)"
    try:
        debian.check()
    except Exception as err:  # noqa: BLE001 - the reason to skip
        return f"no ROS 1 here: {err}"
    return ""


def ended(out: Path, team: str) -> str:
    """How the team's run ended, from its grade, and its pacing (holds, capped ticks: a capped
    tick is where the machine's pace can reach the log), what a failed comparison says."""
    grade, run = out / team / "room.grade.json", out / team / "room.run.json"
    if not grade.is_file():
        return f"{team}: no grade"
    data = json.loads(grade.read_text(encoding="utf-8"))
    pacing = json.loads(run.read_text(encoding="utf-8")).get("pacing") if run.is_file() else "?"
    return f"{team}: {data.get('outcome')}: {data.get('outcome_reason', '')}; pacing: {pacing}"


def pacing(said: str) -> str:
    """The recorder's ``Pacing:`` line (holds and capped ticks of the lone run)."""
    return next((line.strip() for line in said.splitlines() if "Pacing: " in line), "?")


def messages(log: Path) -> list[tuple[str, int, str]]:
    """(topic, log time, digest of the bytes) of every message, in the file's order."""
    return [
        (m.topic, m.log_time_ns, hashlib.sha256(m.data).hexdigest())
        for m in bag.BagReader(log).messages(decode_messages=False)
    ]


@pytest.mark.skipif(bool(_ready()), reason=_ready() or "ready")
def test_a_teams_log_is_the_same_whoever_runs_beside_it(
    tmp_path: Path, module_build_cache: Path
) -> None:
    room = tmp_path / "room.toml"
    save(one_room(), room)
    alone = tmp_path / "alone.mcap"
    done = usar(
        "record", "--scenario", str(room), "--ros1", str(COURSE), "--out", str(alone),
        "--max-sim-time", SIM_S, *SLOW_OK,
    )  # fmt: skip
    assert done.returncode == 1, done.stdout + done.stderr  # stopped at --max-sim-time
    assert "Pacing: " in done.stdout
    expected = messages(alone)
    assert len(expected) > 1000
    print("alone:", pacing(done.stdout))  # shown with -rP: the VM check reads it

    pair = tmp_path / "pair"
    for team in ("a", "b"):
        shutil.copytree(COURSE, pair / team)
    limit = ("--jobs", "2", "--quiet", "--max-sim-time", SIM_S, *SLOW_OK)
    started = time.monotonic()  # sizes the spinner (below), asserts nothing
    code, said = run_batch(pair, room, tmp_path / "pair_out", *limit)
    pair_s = time.monotonic() - started  # a batch of two runs, the build cached
    assert code == 0, said  # every run graded
    for team in ("a", "b"):
        got = messages(tmp_path / "pair_out" / team / "room.mcap")
        assert got == expected, (
            f"team {team} beside itself: {len(got)} vs {len(expected)} messages; "
            + ended(tmp_path / "pair_out", team)
            + f"; alone: {pacing(done.stdout)}"
        )

    spun = tmp_path / "spun"
    shutil.copytree(COURSE, spun / "honest")
    (spun / "spinner.py").write_text(SPINNER.format(spin_s=round(pair_s + 5)), encoding="utf-8")
    code, said = run_batch(spun, room, tmp_path / "spun_out", *limit)
    assert code in (0, 1), said
    got = messages(tmp_path / "spun_out" / "honest" / "room.mcap")
    assert got == expected, (
        f"beside a spinning team: {len(got)} vs {len(expected)} messages; "
        + ended(tmp_path / "spun_out", "honest")
        + f"; alone: {pacing(done.stdout)}"
    )
