"""`usar doctor` (cli/commands/doctor): a line per part of the machine within 100 columns, what
a missing part means, exit 0 for a whole isolation and 1 for a partial one."""

from __future__ import annotations

import pytest

from usar_replay.cli.main import main
from usar_replay.sandbox import cpu_sets


def test_doctor_says_each_part(capsys: pytest.CaptureFixture[str]) -> None:
    code = main(["doctor"])
    out = capsys.readouterr().out
    assert code in (0, 1)
    for part in ("kernel sandbox", "cgroups", "CPU sets", "real-time priority", "ROS 1"):
        assert part in out
    assert all(len(line) <= 100 for line in out.splitlines())
    assert out.rstrip().endswith("isolation here" if code == 0 else "isolation is partial here")


def test_a_missing_part_exits_1_and_says_what_to_do(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.setattr(cpu_sets, "usable_cpus", lambda: [])
    assert main(["doctor"]) == 1
    out = capsys.readouterr().out
    assert "MISS CPU sets" in out and "run one at a time" in " ".join(out.split())
