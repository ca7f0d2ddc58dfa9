"""pipeline/status_line: the record status line with several nodes logging."""

from __future__ import annotations

from usar_replay.core import msgs
from usar_replay.pipeline.status_line import NodeLines


def test_a_repeated_line_does_not_take_the_status_line() -> None:
    lines = NodeLines()
    lines.note(msgs.Log(name="follower", msg="follower: waiting"))
    lines.note(msgs.Log(name="/explorer", msg="explorer: at target_1"))
    lines.note(msgs.Log(name="follower", msg="follower: waiting"))
    assert lines.status() == "[explorer] explorer: at target_1"
    lines.note(msgs.Log(name="follower", msg="follower: to marker 0"))
    assert lines.status() == "[follower] follower: to marker 0"


def test_one_node_shows_its_line_without_a_name_and_only_the_first_line() -> None:
    lines = NodeLines()
    assert lines.status() == ""
    lines.note(msgs.Log(name="/explorer", msg="explorer: home\nsecond line"))
    assert lines.status() == "explorer: home"
    lines.note(msgs.Log(name="explorer", msg=""))
    assert lines.status() == ""
    assert lines.last == {"explorer": ""}  # "/explorer" and "explorer" are one node


def test_per_node_keeps_each_nodes_last_line_in_first_logged_order() -> None:
    lines = NodeLines()
    lines.note(msgs.Log(name="/follower", msg="follower: waiting"))
    lines.note(msgs.Log(name="/explorer", msg="explorer: at target_1"))
    lines.note(msgs.Log(name="/follower", msg="follower: to marker 0"))
    assert lines.per_node() == (
        ("follower", "follower: to marker 0"),
        ("explorer", "explorer: at target_1"),
    )
