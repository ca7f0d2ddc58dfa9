"""sandbox/confinement: one policy for "is untrusted code confined here?", asked by a mission, a
ROS 1 build and a code tool alike; going without says what it costs in the same line."""

from __future__ import annotations

import pytest

from usar_replay.code import tools
from usar_replay.core.errors import UsageError
from usar_replay.process import mission_process
from usar_replay.ros1.building import workspace
from usar_replay.sandbox import confinement, kernel_sandbox


def _callers() -> dict[str, bool]:
    limits = mission_process.MissionLimits()
    return {
        "mission": mission_process.uses_kernel_sandbox(limits),
        "build": workspace.sandboxed(),
        "tool": tools.sandboxed(),
    }


def test_every_caller_gets_the_policys_answer(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("USAR_SANDBOX", raising=False)
    here = confinement.confined()
    assert set(_callers().values()) == {here}
    monkeypatch.setenv("USAR_SANDBOX", "off")
    assert set(_callers().values()) == {False}
    assert confinement.confined("required") is here  # a batch's mode ignores the variable


def test_without_bwrap_auto_goes_unconfined_and_required_refuses_saying_the_cost(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    monkeypatch.delenv("USAR_SANDBOX", raising=False)
    monkeypatch.setattr(kernel_sandbox, "bwrap_available", lambda: (False, "no bwrap here"))
    monkeypatch.setattr(kernel_sandbox, "installed", lambda: False)
    monkeypatch.setattr(confinement, "_warned", False)
    assert set(_callers().values()) == {False}
    warned = capsys.readouterr().err.strip().splitlines()
    assert len(warned) == 1 and warned[0].startswith("usar: warning: no bwrap here")
    assert "world key" in warned[0] and "apt-get install bubblewrap" in warned[0]
    with pytest.raises(UsageError) as err:
        confinement.confined("required")
    line = str(err.value)
    assert "\n" not in line and line.startswith("no bwrap here: usar will not run")
    assert "--no-sandbox" in line and "world key" in line and "usar doctor" in line
    assert confinement.confined("off") is False


def test_bwrap_installed_but_refused_points_to_doctor_not_to_installing_it(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    why = "/usr/bin/bwrap cannot create namespaces here (bwrap: No permissions to create new ns)"
    monkeypatch.delenv("USAR_SANDBOX", raising=False)
    monkeypatch.setattr(kernel_sandbox, "bwrap_available", lambda: (False, why))
    monkeypatch.setattr(kernel_sandbox, "installed", lambda: True)
    monkeypatch.setattr(confinement, "_warned", False)
    assert confinement.confined(warn=True) is False
    warned = capsys.readouterr().err.strip().splitlines()
    assert len(warned) == 1 and "apt-get" not in warned[0]
    assert "`usar doctor`" in warned[0] and "in a container: the flags it lists" in warned[0]
    assert "world key" in warned[0]  # going without says its cost in the same line
    with pytest.raises(UsageError) as err:
        confinement.confined("required")
    line = str(err.value)
    assert "apt-get" not in line and "`usar doctor`" in line and "world key" in line


def test_an_unknown_mode_is_refused() -> None:
    with pytest.raises(ValueError, match="expected auto, required or off"):
        confinement.confined("maybe")
