"""cli/status_display: one line per node on a terminal, one plain line elsewhere."""

from __future__ import annotations

import io
import re

from usar_replay.cli.status_display import MAX_NODE_LINES, StatusDisplay, status_lines
from usar_replay.pipeline.record import Progress

TWO = (("explorer", "explorer: spinning at target_2"), ("follower", "follower: waiting"))


def _progress(t: float, nodes: tuple[tuple[str, str], ...] = TWO) -> Progress:
    return Progress(t, 2, 4, 120, "[explorer] explorer: spinning at target_2", nodes)


def test_two_nodes_get_a_line_each_under_the_status_line() -> None:
    lines = status_lines(_progress(12.0), 99, per_node=True)
    assert lines == [
        "sim    12.0 s | markers 2/4 | frames 120",
        "  [explorer] explorer: spinning at target_2",
        "  [follower] follower: waiting",
    ]


def test_one_node_or_no_terminal_keeps_the_single_line() -> None:
    one = _progress(1.0, (("explorer", "at target_1"),))
    assert status_lines(one, 99, per_node=True) == [
        "sim     1.0 s | markers 2/4 | frames 120 | [explorer] explorer: spinning at target_2"
    ]
    assert len(status_lines(_progress(1.0), 99, per_node=False)) == 1


def test_lines_fit_the_width_escape_control_text_and_many_nodes_are_summed_up() -> None:
    many = tuple((f"node_{k}", "x" * 200 + "\x1b[2J") for k in range(MAX_NODE_LINES + 3))
    lines = status_lines(_progress(3.0, many), 60, per_node=True)
    assert all(len(line) <= 60 for line in lines)
    assert not any("\x1b" in line for line in lines)
    assert len(lines) == 1 + MAX_NODE_LINES + 1
    assert lines[-1] == "  ... and 3 more nodes"


def test_a_terminal_redraws_the_block_in_place() -> None:
    out = io.StringIO()
    display = StatusDisplay(out, tty=True)
    display(_progress(0.5))
    display(_progress(0.7))  # within 0.5 sim-s of the last draw: not drawn
    display(_progress(1.5, (("explorer", "explorer: at target_3"), TWO[1])))
    display.close()
    text = re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", out.getvalue())
    assert "explorer: at target_3" in text and "follower: waiting" in text
    assert "sim     0.7 s" not in text
    assert "\x1b[" in out.getvalue()  # moved the cursor back up to redraw, not scrolled


def test_not_a_terminal_prints_a_plain_line_every_30_sim_seconds() -> None:
    out = io.StringIO()
    display = StatusDisplay(out, tty=False)
    for t in (0.0, 10.0, 29.0, 30.0, 45.0):
        display(_progress(t))
    display.close()
    lines = out.getvalue().splitlines()
    assert [line.split("|")[0] for line in lines] == ["sim     0.0 s ", "sim    30.0 s "]
    assert "\x1b" not in out.getvalue()
