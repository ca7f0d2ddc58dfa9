"""ros1.building.find_package on the shapes real student repositories have (issue 31, point 6).

Each fixture is a folder written here in the shape of a real hand-in: the package in a
subfolder, a catkin workspace (``src/<pkg>``) with its ``build/`` and ``devel/`` committed
(holding stamps named ``package.xml.stamp`` and copies of ``package.xml``), a folder marked
``CATKIN_IGNORE``, several packages of which one builds nodes, several that do. No build runs:
choosing the package is a reading of files.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_replay.batch.plan import discover
from usar_replay.ros1.building.workspace import (
    NoPackage,
    SeveralPackages,
    _copy,
    find_package,
    package_sha256,
)

NODES = "project({name})\nfind_package(catkin REQUIRED)\nadd_executable({name}_node a.cpp)\n"
NO_NODES = "project({name})\nfind_package(catkin REQUIRED)\n# add_executable(none x.cpp)\n"


def pkg(folder: Path, name: str, nodes: bool = True) -> Path:
    folder.mkdir(parents=True)
    (folder / "package.xml").write_text(
        f'<?xml version="1.0"?>\n<package format="2"><name>{name}</name></package>\n',
        encoding="utf-8",
    )
    (folder / "CMakeLists.txt").write_text(
        (NODES if nodes else NO_NODES).format(name=name), encoding="utf-8"
    )
    return folder


def committed_outputs(ws: Path) -> None:
    """What a workspace leaves when its build/ and devel/ are committed: package.xml copies
    and a CATKIN_IGNORE, none of them a package of the team."""
    pkg(ws / "build" / "final_project", "final_project")
    (ws / "build" / "CATKIN_IGNORE").write_text("", encoding="utf-8")
    pkg(ws / "devel" / "share" / "final_project", "final_project")
    pkg(ws / "install" / "share" / "final_project", "final_project")


def test_a_package_folder_is_itself_even_with_its_build_committed(tmp_path: Path) -> None:
    root = pkg(tmp_path / "repo", "final_project")
    committed_outputs(root)
    found = find_package(root)
    assert (found.path, found.name) == (root, "final_project")


def test_a_package_in_a_subfolder_of_the_repository(tmp_path: Path) -> None:
    repo = tmp_path / "repo"
    (repo / "docs").mkdir(parents=True)
    pkg(repo / "group5" / "final_project", "final_project")
    assert find_package(repo).path == repo / "group5" / "final_project"


def test_a_catkin_workspace_with_build_and_devel_committed(tmp_path: Path) -> None:
    ws = tmp_path / "catkin_ws"
    pkg(ws / "src" / "final_project", "final_project")
    committed_outputs(ws)
    pkg(ws / "src" / "old_try", "old_try")
    (ws / "src" / "old_try" / "CATKIN_IGNORE").write_text("", encoding="utf-8")
    pkg(ws / "src" / "fiducial_msgs", "fiducial_msgs", nodes=False)  # usar's own
    assert find_package(ws).path == ws / "src" / "final_project"
    deeper = tmp_path / "repo"  # the workspace one level down in the repository
    deeper.mkdir()
    ws.rename(deeper / "catkin_ws")
    assert find_package(deeper).path == deeper / "catkin_ws" / "src" / "final_project"


def test_of_several_packages_the_one_with_nodes_is_chosen(tmp_path: Path) -> None:
    ws = tmp_path / "ws"
    pkg(ws / "src" / "team_msgs", "team_msgs", nodes=False)
    pkg(ws / "src" / "team_nodes", "team_nodes")
    found = find_package(ws)
    assert (found.path.name, found.name) == ("team_nodes", "team_nodes")


def test_several_packages_with_nodes_are_listed_with_the_option_to_choose(tmp_path: Path) -> None:
    ws = tmp_path / "ws"
    pkg(ws / "src" / "explorer", "explorer")
    pkg(ws / "src" / "follower", "follower")
    with pytest.raises(SeveralPackages) as err:
        find_package(ws)
    text = str(err.value)
    assert "\n" not in text
    assert "2 catkin packages build nodes (src/explorer, src/follower)" in text
    assert f"choose one, e.g. --ros1 {ws / 'src' / 'explorer'}" in text
    (tmp_path / "empty" / "build").mkdir(parents=True)
    pkg(tmp_path / "empty" / "build" / "final_project", "final_project")  # outputs only
    with pytest.raises(NoPackage, match=r"no package\.xml found"):
        find_package(tmp_path / "empty")


def test_a_batch_team_folder_is_found_the_same_way(tmp_path: Path) -> None:
    subs = tmp_path / "subs"
    pkg(subs / "ws_team" / "catkin_ws" / "src" / "final_project", "final_project")
    committed_outputs(subs / "ws_team" / "catkin_ws")
    pkg(subs / "two_team" / "src" / "a", "a")
    pkg(subs / "two_team" / "src" / "b", "b")
    found = {s.team: s for s in discover(subs)}
    assert found["ws_team"].target == f"ros1:{(subs / 'ws_team').resolve()}"
    assert found["two_team"].target == ""
    assert "2 catkin packages build nodes (src/a, src/b)" in found["two_team"].problem


def test_committed_outputs_and_hidden_files_are_not_hashed_or_copied(tmp_path: Path) -> None:
    root = pkg(tmp_path / "p", "p")
    before = package_sha256(find_package(root))
    committed_outputs(root)
    (root / ".cache").mkdir()
    with open(root / ".cache" / "blob.bin", "wb") as f:
        f.truncate(2 * 1024**3)  # 2 GiB, sparse, hidden: issue 33 point 3
    (root / "scripts").mkdir()
    script = root / "scripts" / "node.py"
    script.write_text("#!/usr/bin/python3\n", encoding="utf-8")
    script.chmod(0o755)
    found = find_package(root)
    assert package_sha256(found) != before  # the script counts, nothing else added does
    script.unlink()
    assert package_sha256(found) == before
    script.write_text("#!/usr/bin/python3\n", encoding="utf-8")
    script.chmod(0o755)
    dest = tmp_path / "copy"
    _copy(found, dest)
    copied = sorted(p.relative_to(dest).as_posix() for p in dest.rglob("*") if p.is_file())
    assert copied == ["CMakeLists.txt", "package.xml", "scripts/node.py"]
    assert (dest / "scripts" / "node.py").stat().st_mode & 0o777 == 0o755
