"""ros1.start_prose: a command read from a team's prose as a person reads it (issue 51).

One test per shape students write (a quoted command in a sentence, a numbered step without a
space, a prompt, a bullet, backquotes, a fenced block, nested quotes, trailing punctuation),
and the shell's own rules for what is never a command (an operator ends one, a comment)."""

from __future__ import annotations

import pytest

from usar_replay.ros1.start_prose import clean_name, parse_commands, third_command


def words(text: str) -> list[tuple[str, ...]]:
    return [c.words for c in parse_commands(text)]


@pytest.mark.parametrize(
    ("line", "expected"),
    [
        # the two held-back teams' lines (issue 51)
        (
            '6.Open another terminal and run "rosrun final_project final_project_node" to run '
            "the executable scripts.",
            ("rosrun", "final_project", "final_project_node"),
        ),
        (
            '4. Run command "rosrun final_project final_project_node"',
            ("rosrun", "final_project", "final_project_node"),
        ),
        # single quotes, backquotes, a prompt inside the quotes, a closing full stop
        ("Then 'rosrun p explorer'.", ("rosrun", "p", "explorer")),
        ("Then `$ rosrun p explorer`.", ("rosrun", "p", "explorer")),
        ('Type "$ rosrun p explorer", then wait.', ("rosrun", "p", "explorer")),
        # after a prompt, a bullet, a number with a parenthesis
        ("$ rosrun p explorer", ("rosrun", "p", "explorer")),
        ("# rosrun p explorer", ("rosrun", "p", "explorer")),
        ("> rosrun p explorer", ("rosrun", "p", "explorer")),
        ("- rosrun p explorer", ("rosrun", "p", "explorer")),
        ("* rosrun p explorer", ("rosrun", "p", "explorer")),
        ("4) rosrun p explorer", ("rosrun", "p", "explorer")),
        ("  12. rosrun p explorer.", ("rosrun", "p", "explorer")),
        # a quoted roslaunch with arguments
        (
            '"roslaunch final_project multiple_robots.launch explore:=true"',
            ("roslaunch", "final_project", "multiple_robots.launch", "explore:=true"),
        ),
        # nested quotes: another kind, and the same kind (a student's "..."data: true""")
        (
            """then 'rosservice call /start "data: true"' to begin""",
            ("rosservice", "call", "/start", "data: true"),
        ),
        (
            'Run "rosservice call /start "data: true"" now.',
            ("rosservice", "call", "/start", "data: true"),
        ),
        (
            "rostopic pub -1 /go std_msgs/String \"data: 'hi'\".",
            ("rostopic", "pub", "-1", "/go", "std_msgs/String", "data: 'hi'"),
        ),
        # a word processor's quotes
        (
            "Run \u201crosservice call /start \u201cdata: true\u201d\u201d now.",
            ("rosservice", "call", "/start", "data: true"),
        ),
        ("Run \u2018rosrun p explorer\u2019.", ("rosrun", "p", "explorer")),
        # a comment after it
        ("rosrun p explorer  # the explorer", ("rosrun", "p", "explorer")),
    ],
)
def test_one_command_in_a_line_of_prose(line: str, expected: tuple[str, ...]) -> None:
    assert words(line) == [expected]


def test_a_fenced_block_is_its_commands() -> None:
    text = (
        "## Running\n\n```bash\n$ roslaunch final_project multiple_robots.launch\n"
        "$ rosrun final_project final_project_node\n```\nThat is all.\n"
    )
    got = [(c.words, c.line) for c in parse_commands(text)]
    assert got == [
        (("roslaunch", "final_project", "multiple_robots.launch"), 4),
        (("rosrun", "final_project", "final_project_node"), 5),
    ]


def test_two_commands_of_one_sentence_quoted_or_not() -> None:
    assert words('roslaunch a b.launch and then "rosrun a n".') == [
        ("roslaunch", "a", "b.launch", "and", "then"),
        ("rosrun", "a", "n"),
    ]
    assert words('"roslaunch a b.launch && rosrun a n"') == [
        ("roslaunch", "a", "b.launch"),
        ("rosrun", "a", "n"),
    ]


def test_an_operator_ends_a_command_and_what_follows_is_not_one() -> None:
    line = 'rostopic pub -1 /x std_msgs/String "data: hi" > /tmp/out; rm -rf ~ | sh &'
    assert words(line) == [("rostopic", "pub", "-1", "/x", "std_msgs/String", "data: hi")]
    assert words("echo $(id -u); sleep 1000") == []


def test_an_apostrophe_in_the_prose_keeps_the_words() -> None:
    assert words("rosrun p node (don't forget)")[0][:3] == ("rosrun", "p", "node")


def test_prose_mentioning_a_command_word_is_not_a_command() -> None:
    assert words("We use rosservices and rostopic echo to debug.") == []


@pytest.mark.parametrize(
    ("word", "name"),
    [
        ('final_project_node"', "final_project_node"),
        ("go.launch.", "go.launch"),
        ("node,", "node"),
        ("node**", "node"),
        ("node</code>", "node"),
        ("launch/go.launch", "launch/go.launch"),
        ('"', ""),
    ],
)
def test_clean_name(word: str, name: str) -> None:
    assert clean_name(word) == name


def test_third_command_is_a_service_call_or_a_publish_only() -> None:
    assert third_command('rosservice call /start "data: true"') == (
        "rosservice call /start 'data: true'"
    )
    assert third_command("rostopic pub -1 /go std_msgs/Bool true; reboot") == (
        "rostopic pub -1 /go std_msgs/Bool true"
    )
    assert third_command("echo hi $(id -u); sleep 1000") is None
    assert third_command("rosrun p n") is None
    # a shell around one is read as a person reads it: the command inside, never the shell
    assert third_command("bash -c 'rosservice call /x'") == "rosservice call /x"
