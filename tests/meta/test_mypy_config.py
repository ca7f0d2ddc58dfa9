"""mypy's strictness lives in pyproject.toml, so an editor's mypy and CI run the same check."""

from __future__ import annotations

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_pyproject_sets_strict_mode() -> None:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    assert config["tool"]["mypy"]["strict"] is True


def test_ci_runs_plain_mypy() -> None:
    """CI's command carries no flag of its own: ``mypy usar_replay`` is the whole check."""
    lines = [ln for ln in (ROOT / ".ci" / "run").read_text().splitlines() if "mypy " in ln]
    assert any(ln.split("#")[0].split() == ["mypy", "usar_replay"] for ln in lines), lines
