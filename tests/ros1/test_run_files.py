"""ros1/run_files: what a ROS 1 run leaves in its folder, read as untrusted input (real files,
links and hard links in tmp_path)."""

from __future__ import annotations

import os
from pathlib import Path

from usar_replay.ros1 import run_files


def test_the_run_folder_is_read_as_untrusted(tmp_path: Path) -> None:
    """A node's output is bounded (its start and end kept, the cut said); a symlink or a hard
    link planted in the run's folder is not followed, a bad name not taken."""
    secret = tmp_path / "secret"
    secret.write_text("not the node's\n")
    output = tmp_path / "run" / run_files.OUTPUT_DIR
    output.mkdir(parents=True)
    big = b"first line\n" + b"x" * 1_000_000 + b"\nlast\n"
    (output / "explorer.out").write_bytes(big)
    (output / "planted.out").symlink_to(secret)
    os.link(secret, output / "linked.out")
    (output / "bad name.out").write_text("x")
    kept = dict(run_files.node_outputs(tmp_path / "run"))
    assert list(kept) == ["explorer"]
    text = kept["explorer"]
    assert text.startswith(b"first line\n") and text.endswith(b"\nlast\n")
    assert len(text) < run_files.OUTPUT_HEAD + run_files.OUTPUT_TAIL + 200
    assert b"[usar: 934481 bytes of this node's output left out here" in text
    # the whole output folder replaced by a symlink: nothing is read through it
    os.rename(output, tmp_path / "elsewhere")
    output.symlink_to(tmp_path / "elsewhere")
    assert run_files.node_outputs(tmp_path / "run") == []


def test_a_crash_reason_shows_the_nodes_lines_without_usars_prefix(tmp_path: Path) -> None:
    """roslaunch reports a dead node with its command, usar's prefix included: the reason
    shows the student's command, and each node's last lines from its own file."""
    from usar_replay.ros1.launch_output import _prefix, without_prefix

    out = tmp_path / run_files.OUTPUT_DIR
    out.mkdir()
    (out / "follower.out").write_text("follower: starting\nfollower: cannot go on\n")
    cmd = " ".join([*_prefix(str(out / "follower.out")), "/ws/follower_node", "__name:=follower"])
    died = f"process has died [pid 46, exit code 3, cmd {cmd}]."
    assert without_prefix(died) == (
        "process has died [pid 46, exit code 3, cmd /ws/follower_node __name:=follower]."
    )
    assert (
        run_files.node_tails(out)
        == "[follower] follower: starting\n[follower] follower: cannot go on\n"
    )


def test_the_masters_log_gives_the_parameters_read_and_the_nodes(tmp_path: Path) -> None:
    """From the master's API log: the parameters the package's nodes read (not usar's own
    node's, not those every roscpp node reads) and the nodes that registered (for rosrun)."""
    head = "[rosmaster.master][DEBUG] 2026-11-24 05:40:00,123: "
    calls = [
        "setParam('/usar_sim', '/mission/spin_speed', 0.1)",
        "getParam('/usar_sim', '/mission/xy_tolerance')",
        "getParam('/explorer', '/use_sim_time')",
        "getParam('/explorer', '/mission/spin_speed')",
        "hasParam('/follower', '/mission/spin_speed')",
        "getParam('/follower', '/follower/move_base/actionlib_client_sub_queue_size')",
        "registerPublisher('/explorer', '/explorer/cmd_vel', 'geometry_msgs/Twist', 'http://x/')",
        "registerSubscriber('/usar_sim', '/tf', 'tf2_msgs/TFMessage', 'http://y/')",
        "getSystemState('/usar_sim',)",
    ]
    (tmp_path / run_files.MASTER_LOG).write_text("".join(head + c + "\n" for c in calls))
    assert run_files.parameters_read(tmp_path) == {
        "/mission/spin_speed": ["/explorer", "/follower"]
    }
    assert run_files.registered_nodes(tmp_path) == ["/explorer"]


def test_the_launch_files_nodes_are_read_with_their_names_checked(tmp_path: Path) -> None:
    rows = [
        "/explorer\tusar_course\texplorer_node",
        "/ns/follower\tusar_course\tfollower_node",
        "not a name\tpkg\ttype",
        "/two_fields\tpkg",
        "/long\t" + "p" * 500 + "\ttype",
    ]
    (tmp_path / run_files.NODES_FILE).write_text("\n".join(rows) + "\n", encoding="utf-8")
    assert run_files.launch_nodes(tmp_path) == [
        ("/explorer", "usar_course", "explorer_node"),
        ("/ns/follower", "usar_course", "follower_node"),
        ("/long", "p" * 200, "type"),
    ]
    (tmp_path / run_files.NODES_FILE).unlink()
    assert run_files.launch_nodes(tmp_path) == []  # rosrun: no launch file
    (tmp_path / run_files.NODES_FILE).symlink_to(tmp_path / "elsewhere.tsv")
    (tmp_path / "elsewhere.tsv").write_text("/planted\tp\tt\n", encoding="utf-8")
    assert run_files.launch_nodes(tmp_path) == []  # a link planted there is not followed


def test_the_replaced_nodes_are_read_as_the_launch_files_nodes(tmp_path: Path) -> None:
    rows = "/gazebo\tgazebo_ros\tgzserver\n/explorer/spawn\tgazebo_ros\tspawn_model\nbad\tp\tt\n"
    (tmp_path / run_files.REPLACED_FILE).write_text(rows, encoding="utf-8")
    assert run_files.replaced_nodes(tmp_path) == [
        ("/gazebo", "gazebo_ros", "gzserver"),
        ("/explorer/spawn", "gazebo_ros", "spawn_model"),
    ]
    assert run_files.launch_nodes(tmp_path) == []  # a file of its own


def test_rosgraphs_latest_symlink_race_line_is_left_out(tmp_path: Path) -> None:
    """rospy prints this line when another process renewed ``ROS_LOG_DIR/latest`` at the same
    moment (rosgraph's race: one recording of a class had it, the Ray engine's did not, and
    it names the host's folder): a node's output is kept without it, all else as written."""
    out = tmp_path / run_files.OUTPUT_DIR
    out.mkdir()
    race = (
        "INFO: cannot create a symlink to latest log directory: [Errno 2] No such file or "
        f"directory: '{tmp_path}/ros_log/latest'\n"
    )
    (out / "explorer.out").write_text(race + "[INFO] [/explorer]: explorer up\n")
    (out / "follower.out").write_text(
        "[INFO] [/follower]: up\nINFO: cannot create a symlink to latest log directory\n"
        "my INFO: cannot create a symlink to latest log directory\n"
    )
    assert run_files.node_outputs(tmp_path) == [
        ("explorer", b"[INFO] [/explorer]: explorer up\n"),
        ("follower", b"[INFO] [/follower]: up\nmy INFO: cannot create a symlink to latest log "
                     b"directory\n"),
    ]  # fmt: skip
