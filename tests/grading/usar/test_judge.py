"""The rubric whole: a clean run passes every line, and the rubric stays pure."""

from __future__ import annotations

import subprocess
import sys

import pytest
from rubric_streams import (
    good_run,
    world,
)

from usar_replay.grading.usar import (
    Grader,
    judge,
)


def test_a_clean_stream_passes_every_line() -> None:
    g = Grader(world())
    good_run(g)
    checks = judge(g)
    assert [c.id for c in checks if not c.passed] == []
    assert sum(c.points for c in checks) == pytest.approx(60.0)
    assert len(checks) == 2 + 2 + 2 + 1 + 1 + 2 + 1 + 1 + 2  # + one cmd_vel line per robot


def test_the_rubric_imports_no_mcap_and_no_simulator() -> None:
    code = (
        "import sys, usar_replay.grading.usar; "
        "bad = [m for m in ('mcap', 'usar_replay.log.bag', 'pybullet', 'rerun')"
        " if m in sys.modules]; "
        "print(bad)"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
