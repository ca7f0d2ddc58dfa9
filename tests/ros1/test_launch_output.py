"""ros1/launch_output: each node's stdout and stderr in a file of its own, through the prefix
usar adds, run here with a real shell."""

from __future__ import annotations

import shlex
import subprocess
from pathlib import Path

from usar_replay.ros1 import launch_output as lo


def test_file_labels_of_node_names() -> None:
    assert lo.file_label("/explorer") == "explorer"
    assert lo.file_label("/ns/explorer/") == "ns+explorer"
    assert lo.file_label("/") == "node"


def test_the_prefix_sends_both_streams_in_order_and_keeps_the_exit_code(tmp_path: Path) -> None:
    out = tmp_path / "explorer.out"
    out.write_text("earlier run\n", encoding="utf-8")
    node = ["sh", "-c", "echo one; echo two >&2; echo three; exit 3"]
    got = subprocess.run([*lo._prefix(str(out)), *node], capture_output=True, check=False)
    assert got.returncode == 3
    assert got.stdout == b"" and got.stderr == b""
    assert out.read_text(encoding="utf-8") == "earlier run\none\ntwo\nthree\n"  # appended


def test_rosrun_command_names_the_nodes_file(tmp_path: Path) -> None:
    words = shlex.split(lo.rosrun_command(tmp_path, "usar_course", "explorer_node"))
    assert words[-3:] == ["rosrun", "usar_course", "explorer_node"]
    assert str(tmp_path / "explorer_node.out") in words
    launch = shlex.split(lo.launch_command(tmp_path, tmp_path / "nodes.tsv", "pkg", "a.launch"))
    assert launch[:3] == ["python3", "-P", str(Path(lo.__file__).resolve())]
    assert launch[3:] == [str(tmp_path), str(tmp_path / "nodes.tsv"), "-", "pkg", "a.launch"]
    plan = tmp_path / "plan.json"
    planned = shlex.split(lo.launch_command(tmp_path, tmp_path / "n.tsv", "p", "a.launch", plan))
    assert planned[5:] == [str(plan), "p", "a.launch"]
    nodes = shlex.split(lo.nodes_command("p", "a.launch", plan))
    assert nodes[3:] == ["-", "-", str(plan), "--nodes", "p", "a.launch"]


def test_without_prefix_shows_the_command_as_the_student_wrote_it(tmp_path: Path) -> None:
    # roslaunch splits launch-prefix into words and shows the command joined by spaces
    prefix = " ".join(lo._prefix(str(tmp_path / "follower.out")))
    line = (
        f"process has died [pid 12, exit code 1, cmd {prefix} /ws/devel/lib/p/follower __name:=f]"
    )
    assert lo.without_prefix(line) == (
        "process has died [pid 12, exit code 1, cmd /ws/devel/lib/p/follower __name:=f]"
    )
    assert lo.without_prefix("nothing of usar's") == "nothing of usar's"
