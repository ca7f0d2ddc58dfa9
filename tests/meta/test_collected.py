"""Every ``test_*.py`` under ``tests/`` is collected by the README's test command.

Why: pytest skips folders it takes for build output (``norecursedirs``: ``build``, ``dist``,
``venv``, ...) without a word; the 44 tests of the old ``tests/ros1/build/`` never ran in CI
that way (issue 44). This asks pytest itself, with the project's own configuration (what the
README's ``python -m pytest`` reads), which files it collects, every marker included, and
compares that with the files on disk.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TESTS = ROOT / "tests"


def _collected_files() -> set[str]:
    proc = subprocess.run(
        # the README's command, one process, every marker: which files does it collect?
        [sys.executable, "-m", "pytest", "--collect-only", "-q", "-n", "0", "-m", ""],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    files = set()
    for line in proc.stdout.splitlines():
        path, sep, _ = line.partition("::")
        if sep:
            files.add(Path(path).as_posix())
    return files


def test_every_test_file_is_collected() -> None:
    on_disk = {p.relative_to(ROOT).as_posix() for p in TESTS.rglob("test_*.py")}
    on_disk = {p for p in on_disk if "/." not in p and "__pycache__" not in p}
    collected = _collected_files()
    missing = sorted(on_disk - collected)
    assert not missing, f"not collected by `python -m pytest`: {missing}"
    assert "tests/ros1/building/test_jail.py" in collected  # the folder the rename brought in
