"""code/html: the passages side by side, every team's text escaped."""

from __future__ import annotations

from usar_replay.code.html import pairs_html
from usar_replay.code.similarity import Pair, Passage


def test_passages_side_by_side_and_escaped() -> None:
    pair = Pair("a<script>", "b", 0.95, (Passage("x.cpp:1-3", "y.cpp:4-6", "<b>if</b>", "z"),))
    page = pairs_html([pair], 0.6)
    assert "a&lt;script&gt; ~ b: 0.95" in page and "<script>" not in page
    assert "&lt;b&gt;if&lt;/b&gt;" in page and "x.cpp:1-3" in page and "y.cpp:4-6" in page
    assert "default-src 'none'" in page
    assert "No pair" in pairs_html([], 0.6)
