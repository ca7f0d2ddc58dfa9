"""The ``vm`` marker boots a Debian 12 VM (tests/vm/): such a test runs only when ``-m`` names
``vm``. ``-m ''`` (the README's "fast and slow") selects every test, and a VM check under TCG
emulation takes half an hour or more and needs images built beforehand: it must never start
because someone asked for "everything". Skipped, not deselected, so that ``--collect-only -m ''``
still lists these files (tests/meta/test_collected.py)."""

from __future__ import annotations

import re

import pytest


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    named = re.search(r"\bvm\b", str(config.getoption("markexpr") or ""))
    if named:
        return
    skip = pytest.mark.skip(reason="boots a Debian 12 VM: run with `python -m pytest -m vm`")
    for item in items:
        if item.get_closest_marker("vm") is not None:
            item.add_marker(skip)
