"""code/comments: commented-out code counted, prose and doc comments not, the template's
lines never."""

from __future__ import annotations

import codetools

from usar_replay.code.comments import commented_out, looks_like_code
from usar_replay.code.sources import Source


def test_code_lines_read_as_code_and_prose_does_not() -> None:
    for code in ("explorer_client.waitForResult();", 'ROS_INFO("Sending goal");',
                 "if (x > 3) {", "#include <ros/ros.h>", "int x = 3;"):  # fmt: skip
        assert looks_like_code(code), code
    for prose in ("for broadcaster", "wait for the action server to come up",
                  "Move the robot (slowly).", "TODO: fix this", "@brief Reads the targets"):
        assert not looks_like_code(prose), prose


def test_blocks_are_counted_with_the_largest_first() -> None:
    src = Source("src/main.cpp", codetools.PROCEDURAL_MAIN)
    got = commented_out([src])
    assert got.lines == 9
    assert got.largest == 6 and got.where == "src/main.cpp:18"
    assert [b[2] for b in got.blocks] == [6, 3]


def test_doc_comments_are_never_code() -> None:
    got = commented_out([Source("a.cpp", "/// x.call();\n/** y = 2; */\nint z;\n")])
    assert got.lines == 0


def test_the_templates_own_lines_do_not_count() -> None:
    tmpl = frozenset(
        "".join(line.split()) for line in (
            "explorer_client.waitForResult();", 'ROS_INFO("Sending goal");',
            "follower_client.sendGoal(follower_goal);",
            "ros::spinOnce(); //uncomment this if you have subscribers in your code",
        )
    )  # fmt: skip
    src = Source("src/main.cpp", codetools.TEMPLATE_MAIN)
    assert commented_out([src]).lines == 4
    assert commented_out([src], tmpl).lines == 0


def test_code_switched_off_by_if_zero_counts() -> None:
    text = (
        "int a;\n#if 0\nint b;\n#ifdef X\nint c;\n#endif\nint d;\n#endif\nint e;\n"
        "#if 1\nint f;\n#endif\n"
    )
    got = commented_out([Source("a.cpp", text)])
    assert (got.lines, got.largest, got.where) == (5, 5, "a.cpp:3")
