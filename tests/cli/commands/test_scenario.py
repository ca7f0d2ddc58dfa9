"""`usar scenario` (cli/commands/scenario): print, write or check a world."""

from __future__ import annotations

from pathlib import Path

import pytest

from usar_replay.cli.main import main


def test_scenario_writes_a_variant_that_loads_back(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    from usar_replay.world.scenario import course_world
    from usar_replay.world.scenario_toml import load
    from usar_replay.world.variants import make_variant

    out = tmp_path / "demo3.toml"
    assert main(["scenario", "--seed", "3", "--out", str(out), "--check"]) == 0
    assert load(out) == make_variant(course_world(), 3)
    assert "can be completed" in capsys.readouterr().out
    # never replaced silently
    assert main(["scenario", "--out", str(out)]) == 2
    assert load(out).seed == 3


def test_scenario_check_fails_on_a_world_that_breaks_the_rules(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["scenario", "--out", str(tmp_path / "c.toml")]) == 0
    text = (tmp_path / "c.toml").read_text()
    # move target_1 behind the start-strip wall, out of sight of its marker
    bad = text.replace("target_1 = [-1.752882, 3.246192]", "target_1 = [-4.5, 0.6]")
    assert bad != text
    (tmp_path / "bad.toml").write_text(bad)
    capsys.readouterr()
    assert main(["scenario", "--scenario", str(tmp_path / "bad.toml"), "--check"]) == 1
    out = capsys.readouterr().out  # the verdict is plain output, not an error line
    assert "CANNOT be completed" in out and "FAIL  target_1" in out
