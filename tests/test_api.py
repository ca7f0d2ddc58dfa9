"""api: the one import for mission authors names what the docs and the examples import."""

from __future__ import annotations

import ast
import re
from pathlib import Path

from usar_replay import api

ROOT = Path(__file__).resolve().parents[1]


def _api_imports(text: str) -> set[str]:
    """Names imported from usar_replay.api in Python source (a file, or a doc's code block)."""
    names: set[str] = set()
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.ImportFrom) and node.module == "usar_replay.api":
            names.update(a.name for a in node.names)
    return names


def test_every_exported_name_exists() -> None:
    missing = [name for name in api.__all__ if not hasattr(api, name)]
    assert missing == []
    assert len(set(api.__all__)) == len(api.__all__)


def test_the_examples_and_the_docs_import_only_what_api_exports() -> None:
    used: dict[str, set[str]] = {}
    for path in sorted((ROOT / "examples").rglob("*.py")):
        used[str(path.relative_to(ROOT))] = _api_imports(path.read_text(encoding="utf-8"))
    for doc in (ROOT / "docs" / "node-api.md", ROOT / "README.md"):
        blocks = re.findall(r"```python\n(.*?)```", doc.read_text(encoding="utf-8"), re.S)
        names: set[str] = set()
        for block in blocks:  # every python block of the docs parses (a test of the docs too)
            names |= _api_imports(block)
        used[str(doc.relative_to(ROOT))] = names
    assert sum(len(v) for v in used.values()) > 20  # the examples do import the api
    unknown = {
        where: sorted(n - set(api.__all__)) for where, n in used.items() if n - set(api.__all__)
    }
    assert unknown == {}
