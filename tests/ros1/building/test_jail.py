"""ros1/buildjail: a build's commands run jailed, their output kept and the limit they went past
named; on small shell commands (the real catkin builds and the attacks on them:
tests/ros1/building/test_workspace.py, tests/redteam/test_build.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_replay.ros1.building.jail import BuildLimits, _prlimit, run_jailed
from usar_replay.sandbox.kernel_sandbox import bwrap_available

ENV = {"PATH": "/usr/bin:/bin", "LANG": "C"}


@pytest.fixture(params=[True, False], ids=["sandbox", "rlimits-only"])
def sandbox(request: pytest.FixtureRequest) -> bool:
    if request.param and not bwrap_available()[0]:
        pytest.skip("no usable bwrap here")
    return bool(request.param)


def _run(tmp_path: Path, script: str, sandbox: bool, **limits: float) -> tuple[int, str, str]:
    ws = tmp_path / "ws"
    ws.mkdir(exist_ok=True)
    got = run_jailed(
        ["/bin/sh", "-c", script],
        workspace=ws,
        ro_binds=[],
        env=ENV,
        limits=BuildLimits(**limits),  # type: ignore[arg-type]
        sandbox=sandbox,
    )
    return got.code, got.output, got.limit


def test_a_command_runs_in_its_workspace_with_its_output_kept(
    tmp_path: Path, sandbox: bool
) -> None:
    code, output, limit = _run(tmp_path, "echo out; echo err >&2; echo made > f; exit 3", sandbox)
    assert (code, limit) == (3, "")
    assert output == "out\nerr\n"
    assert (tmp_path / "ws" / "f").read_text() == "made\n"


def test_a_file_past_its_limit_is_named(tmp_path: Path, sandbox: bool) -> None:
    code, _, limit = _run(tmp_path, "head -c 3000000 /dev/zero > big", sandbox, file_mb=1)
    assert code != 0
    assert limit == "its file size limit (1 MiB)"
    assert (tmp_path / "ws" / "big").stat().st_size <= 1024 * 1024


def test_the_wall_limit_ends_the_build(tmp_path: Path, sandbox: bool) -> None:
    code, _, limit = _run(tmp_path, "echo started; exec sleep 60", sandbox, wall_s=0.3)
    assert code != 0 and limit == "its 0.3 s wall limit"


def test_in_the_sandbox_the_workspace_is_the_only_place_to_write(tmp_path: Path) -> None:
    if not bwrap_available()[0]:
        pytest.skip("no usable bwrap here")
    outside = tmp_path / "outside"
    outside.mkdir()
    code, output, _ = _run(tmp_path, f"echo x > {outside}/f && echo wrote", True)
    assert code != 0 and "wrote" not in output and not (outside / "f").exists()


def test_prlimit_options() -> None:
    words = _prlimit({"AS": 100, "CPU": 7, "NPROC": 0, "CORE": 0})
    assert words == ["/usr/bin/prlimit", "--as=100:100", "--cpu=7:12", "--core=0:0", "--"]
