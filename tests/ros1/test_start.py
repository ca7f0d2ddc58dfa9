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


# issue 51: what a TA reads, and what a TA does when the written start cannot start


def test_a_quoted_command_in_a_numbered_sentence_is_the_start(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("${PROJECT_NAME}_node", "helper"))
    (pkg / "doc").mkdir()
    (pkg / "doc" / "instructions.txt").write_text(
        "5.Open a terminal and run roslaunch final_project multiple_robots.launch.\n"
        '6.Open another terminal and run "rosrun final_project final_project_node" to run the '
        "executable scripts.\n"
    )
    start = decide(pkg, "final_project")
    assert (start.launch, start.node) == ("multiple_robots.launch", "final_project_node")
    assert start.source == "doc/instructions.txt lines 1, 2"


def test_a_name_the_package_does_not_build_starts_its_only_executable(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("final_project_node",))
    (pkg / "doc").mkdir()
    (pkg / "doc" / "instructions.txt").write_text(
        "1. catkin_make\n2. source devel/setup.bash\n3. roscore\n4. read on\n"
        "5. rosrun final_project final_project_nod\n"
    )
    start = decide(pkg, "final_project")
    assert (start.launch, start.node) == ("", "final_project_node")
    assert start.source == (
        "doc/instructions.txt line 5 names `final_project_nod`, which the package does not "
        "build; started its only executable `final_project_node`"
    )


def test_a_name_the_package_does_not_build_among_several_is_a_line(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("explorer", "follower"))
    (pkg / "README.md").write_text("Run `rosrun final_project explorer_node`.\n")
    with pytest.raises(UnclearStart) as err:
        decide(pkg, "final_project")
    text = str(err.value)
    assert text.startswith(
        "README.md line 1 names `explorer_node`, which the package does not build (it has "
        "explorer, follower)"
    )
    assert "--starts" in text and "\n" not in text


def test_a_script_of_the_package_is_a_name_it_has(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("a", "b"))
    (pkg / "scripts").mkdir()
    (pkg / "scripts" / "go.py").write_text("#!/usr/bin/env python3\n")
    (pkg / "README.md").write_text("rosrun final_project go.py\n")
    assert decide(pkg, "final_project").node == "go.py"


def test_a_build_usar_cannot_read_trusts_the_written_name(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("a",))
    with (pkg / "CMakeLists.txt").open("a") as f:
        f.write("add_executable(${NODE_NAME} src/x.cpp)\n")
    (pkg / "README.md").write_text("rosrun final_project mystery_node\n")
    start = decide(pkg, "final_project")
    assert (start.node, start.source) == ("mystery_node", "README.md line 1")


def test_a_launch_file_of_that_name_in_another_case_is_started(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("a", "b"))
    (pkg / "launch" / "explore.launch").write_text("<launch/>\n")
    (pkg / "README.md").write_text("roslaunch final_project Explore.launch\n")
    start = decide(pkg, "final_project")
    assert start.launch == "explore.launch"
    assert start.source == (
        "README.md line 1 names `Explore.launch`, which the package does not have; started "
        "its launch file `explore.launch`"
    )


def test_a_missing_launch_file_with_no_fallback_is_a_line(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("a", "b"))
    (pkg / "README.md").write_text("roslaunch final_project nowhere.launch\n")
    with pytest.raises(UnclearStart, match=r"^README.md line 1 names `nowhere.launch`, which"):
        decide(pkg, "final_project")


def test_the_worlds_launch_file_missing_beside_a_node_is_left_out(tmp_path: Path) -> None:
    pkg = tmp_path / "p"
    pkg.mkdir()
    (pkg / "package.xml").write_text("<package><name>final_project</name></package>\n")
    (pkg / "CMakeLists.txt").write_text("project(final_project)\nadd_executable(a a.cpp)\n")
    (pkg / "README.md").write_text(
        "roslaunch final_project multiple_robots.launch\nrosrun final_project a\n"
    )
    start = decide(pkg, "final_project")
    assert (start.launch, start.node) == ("", "a")
    assert start.source.startswith("README.md line 2; line 1 names `multiple_robots.launch`")


# issue 50: the team's usar.toml is the team's word; the instructor's lives outside the folder


def test_the_teams_usar_toml_third_commands_are_never_shell_text(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("a",))
    (pkg / "usar.toml").write_text(
        "[ros1]\nnode = \"a\"\nafter_launch = ['echo rt $(id -u); sleep 1000', "
        "'rosservice call /start \"data: true\"']\n"
    )
    start = decide(pkg, "final_project")
    assert start.after_launch == ("rosservice call /start 'data: true'",)
    assert start.source == (
        "the team's usar.toml [ros1]; after_launch 1 left out: not a rosservice call or "
        "rostopic pub"
    )


def test_the_teams_usar_toml_naming_a_missing_node_falls_back_as_a_text(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("final_project_node",))
    (pkg / "usar.toml").write_text('[ros1]\nnode = "final_project_nod"\n')
    start = decide(pkg, "final_project")
    assert start.node == "final_project_node"
    assert start.source.startswith("the team's usar.toml [ros1]; node 'final_project_nod'")


def test_the_instructors_start_wins_over_the_teams_files(tmp_path: Path) -> None:
    from usar_replay.ros1.starts_file import InstructorStart

    pkg = template(tmp_path / "p", nodes=("a", "b"))
    (pkg / "usar.toml").write_text('[ros1]\nnode = "a"\n')
    (pkg / "README.md").write_text("rosrun final_project a\nrosservice call /team_go\n")
    told = InstructorStart(node="b", note="agreed", label="the instructor's starts.toml [p]")
    start = decide(pkg, "final_project", instructor=told)
    assert (start.node, start.after_launch) == ("b", ())
    assert start.source == "the instructor's starts.toml [p]: agreed"
    # only third commands: the team's start, the instructor's third commands
    (pkg / "usar.toml").unlink()
    told = InstructorStart(after_launch=("rosservice call /go",), label="the instructor's s [p]")
    start = decide(pkg, "final_project", instructor=told)
    assert (start.node, start.after_launch) == ("a", ("rosservice call /go",))
    assert start.source == "README.md line 1; after_launch from the instructor's s [p]"
    with pytest.raises(UnclearStart, match=r"the instructor's s \[p\]: node = 'zz'"):
        decide(
            pkg,
            "final_project",
            instructor=InstructorStart(node="zz", label="the instructor's s [p]"),
        )


def test_the_start_is_checked_against_what_the_build_made(tmp_path: Path) -> None:
    """A name usar trusted before the build (a ``${VAR}`` target) that the build did not make:
    its only built executable, said so; among several, one line; a script of the package's
    own folder with its x bit is runnable, one committed without it is not (rosrun refuses it:
    the team's code never ran). The command line's name gets no fallback."""
    from usar_replay.ros1.start import as_built

    pkg = template(tmp_path / "src" / "p", nodes=())
    (pkg / "scripts").mkdir()
    (pkg / "scripts" / "go.py").write_text("#!/usr/bin/env python3\n")
    (pkg / "scripts" / "go.py").chmod(0o755)
    (pkg / "scripts" / "plain.py").write_text("#!/usr/bin/env python3\n")  # 0644, as unzipped
    devel = tmp_path / "devel"
    lib = devel / "lib" / "final_project"
    lib.mkdir(parents=True)
    (lib / "real_node").write_text("")
    (lib / "real_node").chmod(0o755)
    (lib / "data.txt").write_text("")  # not executable: not a node
    assert as_built("go.py", "README.md line 1", pkg, devel, "final_project").node == "go.py"
    assert as_built("real_node", "x", pkg, devel, "final_project").source == "x"
    got = as_built("mystery_node", "README.md line 1", pkg, devel, "final_project")
    assert (got.node, got.source) == (
        "real_node",
        "README.md line 1; `mystery_node` was not built; started its only executable `real_node`",
    )
    got = as_built("plain.py", "README.md line 2", pkg, devel, "final_project")
    assert (got.node, got.source) == (
        "real_node",
        "README.md line 2; `plain.py` is scripts/plain.py with no x bit; started its only "
        "executable `real_node`",
    )
    with pytest.raises(UnclearStart, match=r"^--node: `mystery_node` was not built, so rosrun"):
        as_built("mystery_node", "--node", pkg, devel, "final_project")
    (lib / "other_node").write_text("")
    (lib / "other_node").chmod(0o755)
    with pytest.raises(UnclearStart, match=r"built other_node, real_node\); the instructor"):
        as_built("mystery_node", "README.md line 1", pkg, devel, "final_project")
    with pytest.raises(UnclearStart, match=r"`plain.py` is scripts/plain.py with no x bit, so"):
        as_built("plain.py", "README.md line 2", pkg, devel, "final_project")
    # no devel/ (a build that left none): not judged here
    assert as_built("mystery_node", "s", pkg, tmp_path / "none", "final_project").node == (
        "mystery_node"
    )


def test_a_renamed_output_trusts_the_written_name_until_the_build(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", nodes=("final_project_node",))
    with (pkg / "CMakeLists.txt").open("a") as f:
        f.write('set_target_properties(final_project_node PROPERTIES OUTPUT_NAME node PREFIX "")\n')
    (pkg / "README.md").write_text("rosrun final_project node\n")
    assert decide(pkg, "final_project").node == "node"


def test_a_text_calling_the_package_by_its_old_name_starts_both_commands(tmp_path: Path) -> None:
    """A package renamed from the template whose instructions still say ``final_project`` for
    both commands: the launch file is the package's, so the ``rosrun`` of that name is too, and
    its executable the package's only one, on record (a real Fall 2021 shape: only the launch
    file was started and the explorer never moved)."""
    pkg = template(tmp_path / "p", name="urban_search_rescue", nodes=("urban_search_rescue_node",))
    (pkg / "doc").mkdir()
    (pkg / "doc" / "instructions.txt").write_text(
        'Open a new terminal and run the command "roslaunch final_project multiple_robots.launch"\n'
        'After launching, open a new terminal and run the command "rosrun final_project '
        'final_project_node"\n'
    )
    start = decide(pkg, "urban_search_rescue")
    assert (start.launch, start.node) == ("multiple_robots.launch", "urban_search_rescue_node")
    assert start.source == (
        "doc/instructions.txt lines 1, 2; line 2 names `final_project_node`, which the package "
        "does not build; started its only executable `urban_search_rescue_node`"
    )


def test_an_old_name_is_not_taken_once_the_text_writes_the_packages_own(tmp_path: Path) -> None:
    pkg = template(tmp_path / "p", name="group9", nodes=("a", "b"))
    (pkg / "README.md").write_text(
        "roslaunch final_project multiple_robots.launch\nrosrun final_project helper\n"
        "rosrun group9 a\n"
    )
    start = decide(pkg, "group9")
    assert (start.launch, start.node) == ("multiple_robots.launch", "a")
