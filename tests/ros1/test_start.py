"""ros1.start: a team's package started as its instructions, README or usar.toml say (issue 42).

The fixtures are shaped as the course's real packages are: the template's dozen launch files,
``doc/instructions.txt`` with the handout's two commands among prose and prompts, a README with
a launch file and a third command, packages with no instructions and one or two nodes.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
from class_folder import TEMPLATE_LAUNCH

from usar_replay.core.errors import UnclearStart, UsageError
from usar_replay.ros1.start import decide, executables, parse_commands


def template(root: Path, name: str = "final_project", nodes: tuple[str, ...] = ("main",)) -> Path:
    """A package shaped as the course template: 12 launch files, ``add_executable`` lines."""
    root.mkdir(parents=True, exist_ok=True)
    (root / "package.xml").write_text(f"<package><name>{name}</name></package>\n")
    exes = "".join(f"add_executable({n} src/{n}.cpp)\n" for n in nodes)
    (root / "CMakeLists.txt").write_text(
        f"project({name})\n# add_executable(old_node src/old.cpp)\n{exes}"
    )
    (root / "launch").mkdir()
    for launch in TEMPLATE_LAUNCH:
        (root / "launch" / launch).write_text("<launch/>\n")
    return root


def test_instructions_name_the_world_and_the_node(tmp_path: Path) -> None:
    pkg = template(tmp_path / "team", nodes=("${PROJECT_NAME}_node",))
    (pkg / "doc").mkdir()
    (pkg / "doc" / "instructions.txt").write_text(
        "Build with catkin build, then source devel/setup.bash.\n"
        "1. In a terminal:\n"
        "   $ roslaunch final_project multiple_robots.launch\n"
        "2. In another one: `rosrun final_project final_project_node`\n"
        "To see the frames: rosrun rviz rviz\n"
    )
    start = decide(pkg, "final_project")
    assert (start.launch, start.node, start.after_launch) == (
        "multiple_robots.launch",
        "final_project_node",
        (),
    )
    assert start.source == "doc/instructions.txt lines 3, 4"
    assert start.commands("final_project") == [
        "roslaunch final_project multiple_robots.launch",
        "rosrun final_project final_project_node",
    ]


def test_a_readme_names_a_launch_file_and_a_service_call(tmp_path: Path) -> None:
    team = tmp_path / "group7"
    pkg = template(team / "final_project")
    (team / "README.md").write_text(
        "# Group 7\n\n```bash\ncd ~/catkin_ws && catkin_make\nroslaunch final_project go.launch\n"
        'rosservice call /start "data: true"\n```\n'
    )
    start = decide(pkg, "final_project", team_dir=team)
    assert (start.launch, start.node) == ("go.launch", "")
    assert start.after_launch == ("rosservice call /start 'data: true'",)
    assert start.source == "README.md line 5"


def test_a_team_launch_file_beside_the_world_one_is_the_start(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p")
    (pkg / "README").write_text(
        "roslaunch final_project multiple_robots.launch\nroslaunch final_project go.launch\n"
    )
    assert decide(pkg, "final_project").launch == "go.launch"


def test_instructions_come_before_the_readme(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("a", "b"))
    (pkg / "README.md").write_text("rosrun final_project a\n")
    (pkg / "doc").mkdir()
    (pkg / "doc" / "instructions.txt").write_text("rosrun final_project b\n")
    assert decide(pkg, "final_project").node == "b"


def test_no_instructions_and_one_node(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("solo_node",))
    (pkg / "README.md").write_text("Our project. Run it as usual.\n")
    start = decide(pkg, "final_project")
    assert (start.launch, start.node) == ("", "solo_node")
    assert start.source == "the package's only executable"


def test_no_instructions_and_two_nodes_names_the_candidates(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("explorer_node", "follower_node"))
    with pytest.raises(UnclearStart) as err:
        decide(pkg, "final_project")
    text = str(err.value)
    assert "explorer_node, follower_node" in text and "--starts FILE" in text
    assert "\n" not in text and isinstance(err.value, UsageError)


def test_usar_toml_overrides_the_text(tmp_path: Path) -> None:
    team = tmp_path / "t"
    pkg = template(team / "src" / "final_project", nodes=("a", "b"))
    (team / "README.md").write_text("rosrun final_project a\n")
    (team / "usar.toml").write_text(
        '[ros1]\nnode = "b"\nafter_launch = ["rostopic pub -1 /go std_msgs/Bool true"]\n'
    )
    start = decide(pkg, "final_project", team_dir=team)
    assert (start.node, start.after_launch, start.source) == (
        "b",
        ("rostopic pub -1 /go std_msgs/Bool true",),
        "the team's usar.toml [ros1]",
    )


def test_usar_toml_naming_a_missing_launch_file_says_so(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p")
    (pkg / "usar.toml").write_text('[ros1]\nlaunch = "nope.launch"\n')
    with pytest.raises(UnclearStart, match=r"nope\.launch.*no such launch file"):
        decide(pkg, "final_project")


def test_the_command_line_wins(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("a", "b"))
    (pkg / "usar.toml").write_text('[ros1]\nnode = "a"\n')
    start = decide(pkg, "final_project", node="b", launch="go.launch")
    assert (start.launch, start.node, start.source) == ("go.launch", "b", "--launch and --node")


def test_other_packages_commands_are_not_the_start(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("a", "b"))
    (pkg / "README.md").write_text(
        "roslaunch turtlebot3_gazebo turtlebot3_world.launch\nrosrun rviz rviz\n"
        "rosrun tf tf_echo map marker_frame\n"
    )
    with pytest.raises(UnclearStart):
        decide(pkg, "final_project")


def test_two_team_nodes_in_the_text_are_unclear(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("a", "b"))
    (pkg / "README.md").write_text("rosrun final_project a\nrosrun final_project b\n")
    with pytest.raises(UnclearStart, match=r"README.md starts 2 things .*\(a, b\)"):
        decide(pkg, "final_project")


def test_a_renamed_package_keeps_the_templates_name_in_its_text(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", name="group9", nodes=("group9_node",))
    (pkg / "README.md").write_text("rosrun final_project group9_node\n")
    assert decide(pkg, "group9").node == "group9_node"


def test_hostile_texts_are_not_followed(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("a", "b"))
    secret = tmp_path / "secret.txt"
    secret.write_text("rosrun final_project a\n")
    (pkg / "doc").mkdir()
    (pkg / "doc" / "instructions.txt").symlink_to(secret)
    os.mkfifo(pkg / "README.md")  # a FIFO: never opened for a blocking read
    with pytest.raises(UnclearStart):
        decide(pkg, "final_project")


def test_parse_commands_reads_prompts_spans_and_chains() -> None:
    text = (
        "Run `roslaunch p w.launch` and then `rosrun p n __name:=x`\n"
        "$ source devel/setup.bash && rosrun p m; rostopic pub /a std_msgs/Empty '{}'\n"
        "no command here\n"
    )
    got = [(c.words, c.line) for c in parse_commands(text)]
    assert got == [
        (("roslaunch", "p", "w.launch"), 1),
        (("rosrun", "p", "n", "__name:=x"), 1),
        (("rosrun", "p", "m"), 2),
        (("rostopic", "pub", "/a", "std_msgs/Empty", "{}"), 2),
    ]


def test_executables_include_installed_python_scripts(tmp_path: Path) -> None:
    (tmp_path / "CMakeLists.txt").write_text(
        "project(p)\nadd_executable(${PROJECT_NAME}_node src/a.cpp)\n"
        "catkin_install_python(PROGRAMS scripts/go.py\n"
        "  DESTINATION ${CATKIN_PACKAGE_BIN_DESTINATION})\n"
    )
    assert executables(tmp_path, "p") == ["go.py", "p_node"]
