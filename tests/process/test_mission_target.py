"""What ``--mission`` names: a reference mission, a ``.py`` file (``:function``), or
``module:function``; its source's sha256 for the log; a bad one is a one-line UsageError; the
loader imports it (a file with its helpers beside it)."""

from __future__ import annotations

import hashlib
import sys
import textwrap
from pathlib import Path

import pytest

from usar_replay.core.errors import UsageError
from usar_replay.process.mission_target import FILE_MODULE, MissionTarget, load, resolve_target


def _sha(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture
def isolated_imports(monkeypatch: pytest.MonkeyPatch) -> None:
    """What :func:`load` adds to ``sys.path`` and ``sys.modules`` goes at the test's end."""
    monkeypatch.setattr(sys, "path", list(sys.path))
    monkeypatch.setattr(sys, "modules", dict(sys.modules))


def test_builtin_is_the_courses_reference_mission() -> None:
    import usar_replay.missions.usar as usar_mission

    for spec in (None, "", "builtin"):
        t = resolve_target(spec)
        assert t.spec == "builtin"
        assert (t.module, t.attribute) == ("usar_replay.missions.usar", "main")
        assert t.path == usar_mission.__file__
        assert t.sha256 == _sha(Path(usar_mission.__file__))
        assert t.is_usar_module and not t.is_file
        assert t.submission_roots() == []  # usar's own: bound with usar's package


def test_a_file_with_and_without_a_function(tmp_path: Path) -> None:
    f = tmp_path / "team7" / "mission.py"
    f.parent.mkdir()
    f.write_text("def main():\n    pass\n", encoding="utf-8")
    t = resolve_target(str(f))
    assert t == MissionTarget(str(f), FILE_MODULE, "main", str(f.resolve()), _sha(f))
    assert t.is_file and t.submission_roots() == [str(f.parent.resolve())]
    named = resolve_target(f"{f}:start")
    assert (named.module, named.attribute, named.path) == (FILE_MODULE, "start", str(f.resolve()))


def test_a_module_and_function_on_the_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    pkg = tmp_path / "team_pkg" / "sub"
    pkg.mkdir(parents=True)
    (tmp_path / "team_pkg" / "__init__.py").write_text("", encoding="utf-8")
    (pkg / "__init__.py").write_text("", encoding="utf-8")
    (pkg / "go.py").write_text("def run():\n    pass\n", encoding="utf-8")
    monkeypatch.syspath_prepend(str(tmp_path))
    t = resolve_target("team_pkg.sub.go:run")
    assert (t.module, t.attribute, t.path) == ("team_pkg.sub.go", "run", str(pkg / "go.py"))
    assert t.sha256 == _sha(pkg / "go.py")
    # what the sandboxed mission reads: the folder its top package was found in
    assert t.module_root() == str(tmp_path)
    assert t.submission_roots() == [str(tmp_path)]
    assert resolve_target("team_pkg.sub.go").attribute == "main"
    # a package's __init__ is found one level further down
    assert resolve_target("team_pkg.sub").module_root() == str(tmp_path)


@pytest.mark.parametrize(
    ("spec", "says"),
    [
        ("nowhere/mission.py", "--mission nowhere/mission.py: no such file; give a .py file"),
        ("no_such_module_xyz:main", "cannot find module 'no_such_module_xyz'"),
        ("no_such_pkg_xyz.deeper", "cannot find module 'no_such_pkg_xyz.deeper'"),
        ("ros1:team7 --launch x", "is a ROS 1 package: only Python missions are re-run here"),
    ],
)
def test_a_bad_target_is_one_usage_line(spec: str, says: str) -> None:
    with pytest.raises(UsageError) as err:
        resolve_target(spec)
    assert says in str(err.value)
    assert "\n" not in str(err.value)


@pytest.mark.usefixtures("isolated_imports")
def test_load_a_file_whose_helpers_lie_beside_it(tmp_path: Path) -> None:
    (tmp_path / "helper_of_team7.py").write_text("VALUE = 42\n", encoding="utf-8")
    f = tmp_path / "mission.py"
    f.write_text(
        textwrap.dedent(
            """
            import helper_of_team7

            def main():
                return helper_of_team7.VALUE
            """
        ),
        encoding="utf-8",
    )
    module = load(resolve_target(str(f)))
    assert module.__name__ == FILE_MODULE
    assert module.main() == 42
    assert sys.modules[FILE_MODULE] is module
    assert sys.path[0] == str(tmp_path)


@pytest.mark.usefixtures("isolated_imports")
def test_load_a_module(tmp_path: Path) -> None:
    (tmp_path / "team_mod_xyz.py").write_text("def main():\n    return 'ok'\n", encoding="utf-8")
    sys.path.insert(0, str(tmp_path))
    module = load(resolve_target("team_mod_xyz:main"))
    assert module.main() == "ok"


@pytest.mark.usefixtures("isolated_imports")
def test_what_the_users_module_raises_is_its_own(tmp_path: Path) -> None:
    f = tmp_path / "broken.py"
    f.write_text("raise RuntimeError('my bug')\n", encoding="utf-8")
    with pytest.raises(RuntimeError, match="my bug"):
        load(resolve_target(str(f)))
