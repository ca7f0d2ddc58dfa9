"""Helpers for tests on real processes: a Python child, and polling a condition (never a
fixed sleep)."""

from __future__ import annotations

import subprocess
import sys
import time
from collections.abc import Callable


def child(code: str) -> subprocess.Popen[bytes]:
    """A Python process running ``code``."""
    return subprocess.Popen([sys.executable, "-c", code])


def wait_for(predicate: Callable[[], object], what: str, timeout_s: float = 20.0) -> None:
    """Poll a condition (not a fixed sleep): fail after ``timeout_s``."""
    deadline = time.monotonic() + timeout_s
    while not predicate():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.005)
