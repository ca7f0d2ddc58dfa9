"""ros1/pacing/graph_start: the launch listing the bridge reads before ``/clock`` starts, and
its bounds: a team's launch files decide what it prints, so a listing past its byte cap or its
wall time says nothing, and its process group is ended. (The graph's start itself, node by
node: tests/ros1/test_bridge.py, recordings agree from tick 1.)"""

from __future__ import annotations

import os

import pytest

from usar_replay.ros1.pacing import graph_start

ENV = {"PATH": os.environ.get("PATH", "/usr/bin:/bin")}


def _listing(prefix: str) -> tuple[list[str], dict[str, object] | None]:
    # the prefix ends the shell (exit 0) before roslaunch would run: what it printed is the
    # listing's output
    return graph_start.launch_listing(prefix, "pkg", "x.launch", ENV)


def test_names_and_the_facts_line_are_read() -> None:
    names, facts = _listing("echo /b; echo ' /a'; echo 'usar-facts {\"k\": 1}'; exit 0")
    assert names == ["/a", "/b"] and facts == {"k": 1}


def test_a_failed_listing_says_nothing() -> None:
    assert _listing("echo /a; exit 3") == ([], None)


def test_a_listing_past_its_byte_cap_says_nothing(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(graph_start, "LISTING_CAP", 100_000)
    assert _listing("echo /a; head -c 99000 /dev/zero | tr '\\0' x; echo; exit 0")[0] == ["/a"]
    flood = "echo /a; echo 'usar-facts {}'; head -c 200000 /dev/zero | tr '\\0' x; exit 0"
    assert _listing(flood) == ([], None)
    assert _listing("echo /a; yes /flood") == ([], None)  # never ends by itself: killed


def test_a_listing_past_its_wall_time_is_ended(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(graph_start, "LISTING_WALL_S", 0.5)
    assert _listing("echo /a; sleep 30 & wait; exit 0") == ([], None)
